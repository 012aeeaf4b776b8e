"""softhap.Mesh: an immutable tetrahedral mesh (sh_mesh)."""

from __future__ import annotations

import ctypes
import os
from typing import Any, Optional, Union

import numpy as np
from numpy.typing import ArrayLike

from . import _arrays
from ._lib import Status, sh_mesh_info
from ._handle import OwnedHandle
from ._loaded import check, lib
from ._record import MeshInfo, record_of
from .mesh_exchange import read_with_meshio, rotation_matrix, tets_of_meshio, to_meshio_mesh, unit_scale, warn_if_implausible


class Mesh(OwnedHandle):
    """An immutable tetrahedral mesh: nodes (m), tets reoriented to positive volume and the
    outward surface. Wraps sh_mesh.

    Create one from arrays with Mesh(nodes, tets) or from a file with Mesh.load(path). Bodies
    copy what they need, so a mesh may be closed once the bodies are made. The C object is freed
    by close(), by leaving a ``with`` block, or when the Mesh is garbage collected.
    """

    _kind = "mesh"
    _destroy = "sh_mesh_destroy"

    def __init__(self, nodes: ArrayLike, tets: ArrayLike) -> None:
        """Create a mesh from nodes (n x 3 floats, m) and tets (m x 4 zero-based node indices).

        The C library validates the data (finite coordinates, indices in range, no repeated
        node, no duplicate or zero-volume tet) and raises softhap.Error with status
        SH_ERR_DEGENERATE_MESH naming the element; inverted tets are reoriented and counted in
        info["reoriented_tet_count"]. A wrong array shape raises ValueError.
        """
        self._handle = None
        nodes = _arrays.float_array(nodes, "nodes", (None, 3))
        tets = _arrays.index_array(tets, "tets", (None, 4))
        handle = ctypes.c_void_p()
        check(
            lib.sh_mesh_create(
                _arrays.double_ptr(nodes),
                _arrays.count(nodes.shape[0], "node count"),
                _arrays.int32_ptr(tets),
                _arrays.count(tets.shape[0], "tet count"),
                ctypes.byref(handle),
            ),
            "sh_mesh_create",
        )
        self._handle = handle.value

    @classmethod
    def grid(cls, xs: ArrayLike, ys: ArrayLike, zs: ArrayLike) -> Mesh:
        """The grid of node planes xs, ys, zs (increasing; uneven spacing allowed, m) with each
        cube split into six positively oriented tets along its main diagonal (Kuhn's split,
        conforming between cubes). Nodes x-major (node (i, j, k) is (i * len(ys) + j) * len(zs) + k), tets cube by
        cube."""
        planes = [np.asarray(p, dtype=float) for p in (xs, ys, zs)]
        if any(p.ndim != 1 or p.size < 2 for p in planes):
            raise ValueError("xs, ys and zs must each list at least two planes")
        ny, nz = planes[1].size - 1, planes[2].size - 1
        nodes = np.array(np.meshgrid(*planes, indexing="ij")).reshape(3, -1).T
        cubes = np.array(np.meshgrid(*[np.arange(p.size - 1) for p in planes], indexing="ij")).reshape(3, -1)
        tets = []
        for path in [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]:
            corner = cubes.copy()
            tet = [(corner[0] * (ny + 1) + corner[1]) * (nz + 1) + corner[2]]
            for axis in path:  # walk the cube's edges from its lowest to its highest corner
                corner[axis] += 1
                tet.append((corner[0] * (ny + 1) + corner[1]) * (nz + 1) + corner[2])
            if path in [(0, 2, 1), (1, 0, 2), (2, 1, 0)]:  # an odd walk: positive with 2 and 3 swapped
                tet[2], tet[3] = tet[3], tet[2]
            tets.append(np.stack(tet, axis=1))
        return cls(nodes, np.stack(tets, axis=1).reshape(-1, 4))

    @classmethod
    def box(cls, size: ArrayLike, cells: ArrayLike, origin: ArrayLike = (0.0, 0.0, 0.0)) -> Mesh:
        """The box [origin, origin + size] (m) of cells[0] x cells[1] x cells[2] equal cubes,
        each split into six tets (see grid)."""
        size = _arrays.float_array(size, "size", (3,))
        origin = _arrays.float_array(origin, "origin", (3,))
        cells = [int(c) for c in cells]
        if len(cells) != 3 or min(cells) < 1:
            raise ValueError("cells must be three counts >= 1")
        return cls.grid(*[origin[k] + np.linspace(0.0, size[k], cells[k] + 1) for k in range(3)])

    @classmethod
    def load(cls, path: Union[str, os.PathLike], units: Union[str, float] = "m") -> Mesh:
        """Load a tetrahedral mesh file whose lengths are in units ("m", "cm", "mm", or metres per
        file unit as a number): Gmsh .msh (1, 2.2, 4.1 ASCII), legacy VTK .vtk, VTK XML .vtu
        (ascii) or TetGen .node/.ele read by the C library; any other format meshio reads (binary Gmsh, binary or appended VTU,
        Abaqus, Medit, ...) through meshio if it is installed (pip install meshio). Non-tet
        elements are skipped (counted in info["skipped_element_count"] by the C readers).
        Warns (softhap.UnitsWarning) if the mesh, in metres, is under 1 mm or over 2 m across.

        Raises softhap.Error: SH_ERR_IO if the file cannot be read, SH_ERR_PARSE (message names
        the line) if it is malformed, SH_ERR_UNSUPPORTED for a format the C readers do not take
        (binary data) when meshio is absent or cannot read it either, SH_ERR_DEGENERATE_MESH if
        its data is invalid; ValueError for unknown units.
        """
        scale = unit_scale(units)
        handle = ctypes.c_void_p()
        status = lib.sh_mesh_load(_arrays.path_bytes(path), ctypes.byref(handle))
        if status in (Status.SH_ERR_PARSE, Status.SH_ERR_UNSUPPORTED):
            other = read_with_meshio(path)  # None: meshio absent or it cannot read it either
            if other is not None:
                return cls.from_meshio(other, units=units, origin=str(path))
        check(status, "sh_mesh_load")
        mesh = cls.__new__(cls)
        mesh._handle = handle.value
        if scale != 1.0:
            mesh = mesh.transform(scale)
        info = mesh.info
        warn_if_implausible(info["bounds_min"], info["bounds_max"], str(path))
        return mesh

    @classmethod
    def from_meshio(cls, mesh: Any, units: Union[str, float] = "m", origin: str = "the meshio mesh") -> Mesh:
        """A Mesh from a meshio.Mesh (or any object with .points and .cells as meshio has them:
        blocks with .type and .data, or (type, data) pairs) whose lengths are in units. Its
        "tetra" blocks (and the corner nodes of "tetra10" blocks) make the tets; other cells
        are left out. Warns like load() about implausible sizes; ValueError without tets."""
        points, tets, _skipped = tets_of_meshio(mesh)
        points = points * unit_scale(units)
        warn_if_implausible(points.min(axis=0), points.max(axis=0), origin)
        return cls(points, tets)

    def to_meshio(self) -> Any:
        """This mesh as a meshio.Mesh (points in m, one "tetra" block); needs meshio."""
        return to_meshio_mesh(self.nodes, self.tets)

    def transform(self, scale: float, translation: Optional[ArrayLike] = None,
                  rotation: Optional[ArrayLike] = None) -> Mesh:
        """Return a new Mesh whose nodes are scale * R x + translation: scale > 0 (e.g. 0.01
        for a file in centimetres), R from rotation (a unit quaternion (w, x, y, z) or a 3x3
        rotation matrix; None for none), translation 3 floats (m; None for none). This mesh is
        unchanged. A bad scale raises softhap.Error SH_ERR_INVALID_ARGUMENT, a bad rotation
        ValueError."""
        handle = self._require_handle("sh_mesh_transform")
        if rotation is not None:
            turned = self.nodes @ rotation_matrix(rotation).T
            return Mesh(turned, self.tets).transform(scale, translation)
        if translation is None:
            offset = None
            offset_ptr = None
        else:
            offset = _arrays.float_array(translation, "translation", (3,))
            offset_ptr = _arrays.double_ptr(offset)
        out = ctypes.c_void_p()
        check(
            lib.sh_mesh_transform(handle, float(scale), offset_ptr, ctypes.byref(out)),
            "sh_mesh_transform",
        )
        mesh = Mesh.__new__(Mesh)
        mesh._handle = out.value
        del offset
        return mesh

    def __repr__(self) -> str:
        if self._handle is None:
            return "<softhap.Mesh (closed)>"
        info = self.info
        return "<softhap.Mesh %d nodes, %d tets>" % (info["node_count"], info["tet_count"])

    # -- queries ---------------------------------------------------------------------------

    @property
    def info(self) -> MeshInfo:
        """Facts about the mesh as a MeshInfo (a dict with attribute access): node_count,
        tet_count, surface_triangle_count, edge_count, orphan_node_count, reoriented_tet_count,
        skipped_element_count, bounds_min, bounds_max (m) and volume (m^3)."""
        handle = self._require_handle("sh_mesh_get_info")
        raw = sh_mesh_info()
        check(lib.sh_mesh_get_info(handle, ctypes.byref(raw)), "sh_mesh_get_info")
        return record_of(MeshInfo, raw)

    @property
    def node_count(self) -> int:
        """Number of nodes, including orphans (nodes used by no tet)."""
        return self.info["node_count"]

    @property
    def tet_count(self) -> int:
        """Number of tetrahedra."""
        return self.info["tet_count"]

    @property
    def nodes(self) -> np.ndarray:
        """A copy of the node positions, an (n, 3) float64 array (m)."""
        handle = self._require_handle("sh_mesh_get_nodes")
        out = np.empty((self.node_count, 3), dtype=np.float64)
        check(
            lib.sh_mesh_get_nodes(handle, _arrays.double_ptr(out), out.shape[0]), "sh_mesh_get_nodes"
        )
        return out

    def _int_table(self, function_name: str, rows: int, columns: int) -> np.ndarray:
        handle = self._require_handle(function_name)
        out = np.empty((rows, columns), dtype=np.int32)
        check(getattr(lib, function_name)(handle, _arrays.int32_ptr(out), rows), function_name)
        return out

    @property
    def tets(self) -> np.ndarray:
        """A copy of the tets, an (m, 4) int32 array of node indices (positive orientation)."""
        return self._int_table("sh_mesh_get_tets", self.tet_count, 4)

    @property
    def surface_triangles(self) -> np.ndarray:
        """A copy of the boundary triangles, a (k, 3) int32 array, counter-clockwise seen from
        outside (normals point outward)."""
        return self._int_table(
            "sh_mesh_get_surface_triangles", self.info["surface_triangle_count"], 3
        )

    @property
    def edges(self) -> np.ndarray:
        """A copy of the unique tet edges, an (e, 2) int32 array, smaller index first, sorted."""
        return self._int_table("sh_mesh_get_edges", self.info["edge_count"], 2)

    def write_vtu(self, path: Union[str, os.PathLike]) -> None:
        """Write the mesh as an ASCII VTK XML unstructured grid (.vtu) file."""
        handle = self._require_handle("sh_mesh_write_vtu")
        check(lib.sh_mesh_write_vtu(handle, _arrays.path_bytes(path)), "sh_mesh_write_vtu")
