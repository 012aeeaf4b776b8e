"""softhap.Body: a body of a World (an sh_body_id), its node data, topology and cuts, boundary
conditions and loads."""

from __future__ import annotations

import ctypes
import os
from typing import Optional, Union

import numpy as np
from numpy.typing import ArrayLike

from . import _arrays, _defs
from ._entity import WorldEntity
from ._errors import Error
from ._lib import Status, sh_body_id, sh_body_info, sh_cut_report
from ._loaded import check, lib
from ._record import BodyInfo, CutReport, record_of


def cut_triangles(value: ArrayLike) -> np.ndarray:
    """value (k triangles, as a (k, 3, 3) or (k, 9) array-like of floats) as a C-contiguous
    (k, 9) float64 array, three corners per row; any other shape is a ValueError."""
    try:
        array = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError("triangles must be an array of numbers: %s" % exc) from None
    if array.ndim == 3 and array.shape[1:] == (3, 3) or array.ndim == 2 and array.shape[1] == 9:
        return np.ascontiguousarray(array.reshape(array.shape[0], 9))
    raise ValueError(
        "triangles must have shape (k, 3, 3) or (k, 9), got %s" % (tuple(array.shape),)
    )


def body_id_in(world: object, body: Body, name: str) -> sh_body_id:
    """The id of body, checked to be a Body (else TypeError) of world (else ValueError); name
    is the argument's name for the message."""
    if not isinstance(body, Body):
        raise TypeError("%s must be a softhap.Body, got %s" % (name, type(body).__name__))
    if body.world is not world:
        raise ValueError("%r belongs to another world" % (body,))
    return body._cid


class Body(WorldEntity):
    """A body of a World (an sh_body_id): an FEM body or a mass-spring network.

    Made by World.add_fem_body or World.add_spring_body. The World owns the body's data; a
    Body keeps its World alive. After World.remove_body the id is stale and every call raises
    softhap.Error (SH_ERR_INVALID_HANDLE); so does every call after the World is closed.
    Arrays read from a body are copies.
    """

    _kind = "body"
    _is_valid = "sh_body_is_valid"
    _id_type = sh_body_id

    # -- facts ------------------------------------------------------------------------------

    @property
    def info(self) -> BodyInfo:
        """Facts about the body as a BodyInfo (dict with attribute access): node_count,
        element_count, is_fem, fixed_node_count, total_mass (kg), dt_critical (s),
        surface_triangle_count, reserved and topology_version."""
        handle = self._world_handle("sh_body_get_info")
        raw = sh_body_info()
        check(lib.sh_body_get_info(handle, self._cid, ctypes.byref(raw)), "sh_body_get_info")
        return record_of(BodyInfo, raw, is_fem=bool(raw.is_fem))

    @property
    def node_count(self) -> int:
        """Number of nodes (including orphans); a cut appends nodes, so this can grow."""
        return self.info["node_count"]

    @property
    def tet_count(self) -> int:
        """Number of tets of an FEM body (its element count), after any cuts. A mass-spring
        body raises softhap.Error (SH_ERR_UNSUPPORTED), as Body.tets does."""
        info = self.info
        if not info["is_fem"]:
            raise Error(
                Status.SH_ERR_UNSUPPORTED,
                "tet_count needs an FEM body; this is a mass-spring body (see info.element_count)",
            )
        return info["element_count"]

    @property
    def topology_version(self) -> int:
        """0 at creation; increases at every topology change (a cut). When it moves, arrays
        read before (tets, springs, surface_triangles, node_parents, positions) are stale."""
        return int(self.info["topology_version"])

    @property
    def critical_dt(self) -> float:
        """Critical explicit time step of the body's integrator (s); inf if there is none."""
        return self.info["dt_critical"]

    # -- state ------------------------------------------------------------------------------

    def _read(self, function_name: str, columns: int) -> np.ndarray:
        handle = self._world_handle(function_name)
        n = self.node_count
        out = np.empty((n, columns) if columns else (n,), dtype=np.float64)
        check(
            getattr(lib, function_name)(handle, self._cid, _arrays.double_ptr(out), n),
            function_name,
        )
        return out

    def _node_vectors(self, value: ArrayLike, name: str) -> np.ndarray:
        return _arrays.float_array(value, name, (self.node_count, 3))

    def _write_node_vectors(self, function_name: str, value: ArrayLike, name: str) -> None:
        handle = self._world_handle(function_name)
        array = self._node_vectors(value, name)
        check(
            getattr(lib, function_name)(handle, self._cid, _arrays.double_ptr(array), array.shape[0]),
            function_name,
        )

    @property
    def positions(self) -> np.ndarray:
        """Node positions, an (n, 3) array (m). Reading returns a copy; assigning an (n, 3)
        array sets every position (sh_body_set_positions)."""
        return self._read("sh_body_get_positions", 3)

    @positions.setter
    def positions(self, value: ArrayLike) -> None:
        self._write_node_vectors("sh_body_set_positions", value, "positions")

    @property
    def velocities(self) -> np.ndarray:
        """Node velocities, an (n, 3) array (m/s). Reading returns a copy; assigning an (n, 3)
        array sets every velocity (fixed and orphan nodes keep zero velocity)."""
        return self._read("sh_body_get_velocities", 3)

    @velocities.setter
    def velocities(self, value: ArrayLike) -> None:
        self._write_node_vectors("sh_body_set_velocities", value, "velocities")

    @property
    def masses(self) -> np.ndarray:
        """A copy of the lumped nodal masses, an (n,) array (kg; 0 for orphan nodes)."""
        return self._read("sh_body_get_masses", 0)

    def elastic_forces(self) -> np.ndarray:
        """Internal elastic nodal forces at the current positions, an (n, 3) array (N)."""
        return self._read("sh_body_get_elastic_forces", 3)

    def elastic_energy(self) -> float:
        """Elastic energy stored at the current positions (J)."""
        handle = self._world_handle("sh_body_get_elastic_energy")
        energy = ctypes.c_double()
        check(
            lib.sh_body_get_elastic_energy(handle, self._cid, ctypes.byref(energy)),
            "sh_body_get_elastic_energy",
        )
        return energy.value

    # -- topology and cutting ---------------------------------------------------------------

    def _int_table(self, function_name: str, rows: int, columns: int) -> np.ndarray:
        handle = self._world_handle(function_name)
        out = np.empty((rows, columns) if columns else (rows,), dtype=np.int32)
        check(
            getattr(lib, function_name)(handle, self._cid, _arrays.int32_ptr(out), rows),
            function_name,
        )
        return out

    @property
    def tets(self) -> np.ndarray:
        """A copy of the FEM body's tets in the current topology, an (m, 4) int32 array of node
        indices (positively oriented). A mass-spring body raises softhap.Error
        (SH_ERR_UNSUPPORTED)."""
        info = self.info  # sizes are read at every call: a cut changes them
        rows = info["element_count"] if info["is_fem"] else 0  # a spring body: C refuses it
        return self._int_table("sh_body_get_tets", rows, 4)

    @property
    def springs(self) -> np.ndarray:
        """A copy of the mass-spring body's springs, an (s, 2) int32 array of node indices. An
        FEM body raises softhap.Error (SH_ERR_UNSUPPORTED)."""
        info = self.info
        rows = 0 if info["is_fem"] else info["element_count"]  # an FEM body: C refuses it
        return self._int_table("sh_body_get_springs", rows, 2)

    @property
    def surface_triangles(self) -> np.ndarray:
        """A copy of the FEM body's boundary triangles in the current topology (cut faces
        included), a (k, 3) int32 array, counter-clockwise seen from outside. A mass-spring body
        raises softhap.Error (SH_ERR_UNSUPPORTED)."""
        rows = self.info["surface_triangle_count"]
        return self._int_table("sh_body_get_surface_triangles", rows, 3)

    @property
    def node_parents(self) -> np.ndarray:
        """A copy of each node's parent, an (n,) int32 array: the node a cut made it from (a
        copy's parent is the node copied; a node made on a cut edge has the edge's nearer end),
        -1 for the body's own nodes."""
        return self._int_table("sh_body_get_node_parents", self.node_count, 0)

    def cut(self, triangles: ArrayLike) -> CutReport:
        """Cut the body along a triangulated surface (sh_body_cut) and return a CutReport.

        triangles is a (k, 3, 3) or (k, 9) array-like of floats: k >= 1 triangles, three
        corners each, world frame (m), in the body's current configuration; they need not be
        welded or consistently oriented. The material the surface passes through separates
        (FEM bodies split the tets it crosses, mass-spring bodies lose the springs it crosses);
        where the surface's border lies inside the body, it stays joined until a later cut
        extends it: an FEM body keeps what it was cut along (in its rest shape) and cuts a
        later cut with the earlier ones it continues, so that strips narrower than an element
        (a scripted blade) add up. topology_version increases if anything was cut; node
        indices never change, new nodes are appended.

        A wrong shape raises ValueError; non-finite coordinates, a zero-area triangle or k = 0
        raise softhap.Error (SH_ERR_INVALID_ARGUMENT), and the body is left as it was.
        """
        handle = self._world_handle("sh_body_cut")
        array = cut_triangles(triangles)
        raw = sh_cut_report()
        check(
            lib.sh_body_cut(
                handle,
                self._cid,
                _arrays.double_ptr(array),
                _arrays.count(array.shape[0], "triangle count"),
                ctypes.byref(raw),
            ),
            "sh_body_cut",
        )
        return record_of(CutReport, raw)

    # -- boundary conditions and loads ------------------------------------------------------

    def _node_list(self, function_name: str, indices: ArrayLike) -> None:
        handle = self._world_handle(function_name)
        nodes = _arrays.index_list(indices, "indices")
        check(
            getattr(lib, function_name)(handle, self._cid, _arrays.int32_ptr(nodes), nodes.size),
            function_name,
        )

    def fix_nodes(self, indices: ArrayLike) -> None:
        """Fix the listed nodes (an int or a sequence of indices) at their current positions."""
        self._node_list("sh_body_fix_nodes", indices)

    def release_nodes(self, indices: ArrayLike) -> None:
        """Release fixed or prescribed nodes so that they move freely again."""
        self._node_list("sh_body_release_nodes", indices)

    def prescribe_positions(self, indices: ArrayLike, positions: ArrayLike) -> None:
        """Prescribe target positions ((k, 3), m) of k nodes: each moves linearly to its target
        over the next step and is then held there."""
        handle = self._world_handle("sh_body_prescribe_positions")
        nodes = _arrays.index_list(indices, "indices")
        targets = _arrays.float_array(positions, "positions", (nodes.size, 3))
        check(
            lib.sh_body_prescribe_positions(
                handle,
                self._cid,
                _arrays.int32_ptr(nodes),
                _arrays.double_ptr(targets),
                nodes.size,
            ),
            "sh_body_prescribe_positions",
        )

    def set_external_forces(self, forces: Optional[ArrayLike]) -> None:
        """Set the external nodal forces, an (n, 3) array (N), or None to clear them
        (sh_body_set_external_forces).

        The forces are held: every World.step applies them (and World.solve_static balances
        them) until they are changed by another call or cleared with None. They are not a
        one-step impulse."""
        handle = self._world_handle("sh_body_set_external_forces")
        if forces is None:
            status = lib.sh_body_set_external_forces(handle, self._cid, None, 0)
        else:
            array = self._node_vectors(forces, "forces")
            status = lib.sh_body_set_external_forces(
                handle, self._cid, _arrays.double_ptr(array), array.shape[0]
            )
        check(status, "sh_body_set_external_forces")

    def set_node_damping(self, coefficients: Union[float, ArrayLike, None]) -> None:
        """Set per-node viscous damping c_i (1/s): f_i = -c_i m_i v_i, added to the body's mass
        damping. coefficients is a scalar (every node), an (n,) array, or None to clear."""
        handle = self._world_handle("sh_body_set_node_damping")
        if coefficients is None:
            status = lib.sh_body_set_node_damping(handle, self._cid, None, 0)
        else:
            n = self.node_count
            if np.ndim(coefficients) == 0:
                array = np.full(n, float(coefficients))  # type: ignore[arg-type]
            else:
                array = _arrays.float_array(coefficients, "coefficients", (n,))
            status = lib.sh_body_set_node_damping(handle, self._cid, _arrays.double_ptr(array), n)
        check(status, "sh_body_set_node_damping")

    def set_material(
        self,
        element_indices: ArrayLike,
        model: str = "stvk",
        young: float = 3000.0,
        poisson: float = 0.45,
        density: float = 1000.0,
        toughness: float = 200.0,
    ) -> None:
        """Set the material of the listed elements (a region of an FEM body). Masses are
        recomputed from the new density.

        model is "stvk", "linear", "corotational" or "neohookean"; young (Pa), poisson,
        density (kg/m^3) and toughness (J/m^2, for cutting tools with criterion="physical"). The C API has no per-element material getter, so a field not given
        takes the sh_fem_body_def_default value shown in the signature, not the element's
        current value. Invalid values raise softhap.Error (SH_ERR_INVALID_ARGUMENT).
        """
        arguments = dict(model=model, young=young, poisson=poisson, density=density, toughness=toughness)
        handle = self._world_handle("sh_body_set_material")
        elements = _arrays.index_list(element_indices, "element_indices")
        material = _defs.material(arguments)
        check(
            lib.sh_body_set_material(
                handle, self._cid, _arrays.int32_ptr(elements), elements.size, ctypes.byref(material)
            ),
            "sh_body_set_material",
        )

    # -- output -----------------------------------------------------------------------------

    def write_vtu(self, path: Union[str, os.PathLike]) -> None:
        """Write the body's current shape as an ASCII .vtu file (FEM: tets; springs: lines)
        with point data "velocity"."""
        handle = self._world_handle("sh_body_write_vtu")
        check(
            lib.sh_body_write_vtu(handle, self._cid, _arrays.path_bytes(path)), "sh_body_write_vtu"
        )

    def remove(self) -> None:
        """Remove this body from its world (same as world.remove_body(body))."""
        self._world.remove_body(self)
