"""softhap.viz: hand a body or a mesh to pyvista or polyscope, and render pictures without a
display. Optional (pip install "softhap[viz]" or pyvista / polyscope alone); `import softhap`
never imports this module nor its viewers.

    from softhap import viz
    viz.to_pyvista(body).plot()                          # an interactive window
    viz.screenshot(body, "liver.png", tool=(p, 0.005))   # headless (off-screen) PNG
    viz.to_polyscope(body); polyscope.show()
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence, Tuple, Union

import numpy as np

from .body import Body
from .mesh import Mesh

Shape = Union[Body, Mesh]


def _nodes_and_tets(shape: Shape) -> Tuple[np.ndarray, np.ndarray]:
    """Current nodes and tets of an FEM body (its cut topology included), or of a mesh."""
    if isinstance(shape, Body):
        return shape.positions, shape.tets
    return shape.nodes, shape.tets


def _require(module: str) -> Any:
    try:
        return __import__(module)
    except ImportError as exc:
        raise ImportError("softhap.viz needs %s (pip install %s)" % (module, module)) from exc


def to_pyvista(shape: Shape, rest: Optional[np.ndarray] = None) -> Any:
    """A pyvista.UnstructuredGrid of the tets; with rest (the rest nodes, (n, 3)), point data
    "displacement" (m, vectors) and "displacement_mm" (its length in mm) to colour by (a node a
    cut added shows its oldest ancestor's displacement)."""
    pv = _require("pyvista")
    nodes, tets = _nodes_and_tets(shape)
    cells = np.hstack([np.full((len(tets), 1), 4), tets]).astype(np.int64).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(len(tets), pv.CellType.TETRA, dtype=np.uint8), nodes)
    if rest is not None:
        u = nodes[: len(rest)] - rest
        if len(nodes) > len(rest):  # nodes a cut added: their oldest ancestor's displacement
            ancestor = np.arange(len(nodes))
            parents = shape.node_parents if isinstance(shape, Body) else np.full(len(nodes), -1)
            for _ in range(64):  # a chain of cuts: follow parents back to the rest nodes
                up = (ancestor >= len(rest)) & (parents[np.minimum(ancestor, len(parents) - 1)] >= 0)
                if not up.any():
                    break
                ancestor[up] = parents[ancestor[up]]
            u = np.vstack([u, u[np.minimum(ancestor[len(rest):], len(rest) - 1)]])
        grid.point_data["displacement"] = u
        grid.point_data["displacement_mm"] = 1e3 * np.linalg.norm(u, axis=1)
    return grid


def to_polyscope(shape: Shape, name: str = "softhap body") -> Any:
    """Registers the tets as a polyscope volume mesh named name and returns it (call
    polyscope.init() first, polyscope.show() after)."""
    ps = _require("polyscope")
    nodes, tets = _nodes_and_tets(shape)
    return ps.register_volume_mesh(name, nodes, tets=tets)


def screenshot(shape: Shape, path: Union[str, os.PathLike], rest: Optional[np.ndarray] = None,
               tool: Optional[Tuple[Sequence[float], float]] = None, size: Tuple[int, int] = (800, 600),
               camera: Optional[Sequence[Sequence[float]]] = None) -> None:
    """Renders the shape off-screen into the PNG file path: its surface coloured by the
    displacement from rest (mm) if given; tool, a (centre, radius) sphere; camera, pyvista's
    camera_position ((eye, focus, up)), default an oblique view from above."""
    pv = _require("pyvista")
    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    grid = to_pyvista(shape, rest)
    triangles = shape.surface_triangles  # outward; a body's cut faces included
    surface = pv.PolyData(grid.points, np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel())
    surface.point_data.update(grid.point_data)
    options = {"scalars": "displacement_mm", "cmap": "viridis",
               "scalar_bar_args": {"title": "displacement (mm)"}} if rest is not None else {"color": "#d9a38b"}
    plotter.add_mesh(surface, smooth_shading=True, **options)
    if tool is not None:
        plotter.add_mesh(pv.Sphere(radius=tool[1], center=tuple(tool[0])), color="#b0b8c0")
    if camera is not None:
        plotter.camera_position = [tuple(c) for c in camera]
    else:
        plotter.view_isometric()
    plotter.screenshot(os.fspath(path))
    plotter.close()
