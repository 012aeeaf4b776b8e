"""softhap.tetrahedralize: a closed triangle surface (OBJ, STL, ... or arrays) to a tet mesh,
through an optional meshing backend (pytetwild, fTetWild's Python binding, MPL-2.0)."""

from __future__ import annotations

import os
import tempfile
from typing import Any, Optional, Tuple, Union

import numpy as np

from .mesh import Mesh
from .mesh_exchange import unit_scale, warn_if_implausible


def open_edge_count(triangles: np.ndarray) -> int:
    """Edges of the triangle surface not shared by exactly two triangles (0: closed)."""
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int(np.count_nonzero(counts != 2))


def read_surface(path: Union[str, os.PathLike]) -> Tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of a surface file meshio reads (OBJ, STL, PLY, OFF, ...)."""
    try:
        import meshio
    except ImportError as exc:
        raise ImportError("reading a surface file needs meshio (pip install meshio)") from exc
    surface = meshio.read(path)
    triangles = [np.asarray(block.data) for block in surface.cells if block.type == "triangle"]
    if not triangles:
        raise ValueError("%s holds no triangles" % os.fspath(path))
    return np.asarray(surface.points, dtype=float), np.concatenate(triangles)


def tetrahedralize(surface: Union[str, os.PathLike, Tuple[Any, Any]], units: Union[str, float] = "m",
                   edge_length: Optional[float] = None, quiet: bool = True) -> Mesh:
    """A tet mesh filling the closed triangle surface, which is a file meshio reads (OBJ, STL,
    ...) or a (vertices (n, 3), triangles (m, 3)) pair, in units ("m", "cm", "mm" or metres per unit).

    edge_length: the tets' target edge length (m); None: 1/20 of the bounding box's diagonal.
    The backend is pytetwild (pip install pytetwild; fTetWild, MPL-2.0), which fills the
    surface's envelope robustly, also for surfaces with small defects; an open surface
    (edges not shared by exactly two triangles) is refused with ValueError, since what it
    encloses is undefined. ImportError if pytetwild (or, for a file, meshio) is missing."""
    if isinstance(surface, tuple):
        vertices, triangles = (np.asarray(a) for a in surface)
    else:
        vertices, triangles = read_surface(surface)
    vertices = np.asarray(vertices, dtype=float) * unit_scale(units)
    triangles = np.asarray(triangles, dtype=np.int32)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or triangles.ndim != 2 or triangles.shape[1] != 3:
        raise ValueError("the surface needs vertices (n, 3) and triangles (m, 3)")
    open_edges = open_edge_count(triangles)
    if open_edges:
        raise ValueError("the surface is not closed: %d edges are not shared by exactly two triangles" % open_edges)
    warn_if_implausible(vertices.min(axis=0), vertices.max(axis=0), "the surface")
    try:
        import pytetwild
    except ImportError as exc:
        raise ImportError("softhap.tetrahedralize needs pytetwild (pip install pytetwild)") from exc
    options = {"quiet": quiet}
    if edge_length is not None:
        options["edge_length_abs"] = float(edge_length)
    # fTetWild writes a scratch file (__tracked_surface.stl) into the working directory: run it
    # in a temporary one, so that the caller's is left as it was.
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory() as scratch:
        os.chdir(scratch)
        try:
            nodes, tets = pytetwild.tetrahedralize(vertices, triangles, **options)
        finally:
            os.chdir(cwd)
    e = nodes[tets[:, 1:]] - nodes[tets[:, :1]]
    negative = np.einsum("ij,ij->i", e[:, 0], np.cross(e[:, 1], e[:, 2])) < 0.0
    tets[negative] = tets[negative][:, [0, 1, 3, 2]]  # fTetWild's orientation is the opposite one
    return Mesh(nodes, tets)
