"""softhap.Body: a body of a World (an sh_body_id), its node data, boundary conditions and loads."""

from __future__ import annotations

import ctypes
import os
from typing import Optional, Union

import numpy as np
from numpy.typing import ArrayLike

from . import _arrays, _defs
from ._entity import WorldEntity
from ._lib import sh_body_id, sh_body_info
from ._loaded import check, lib
from ._record import BodyInfo, record_of


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
        element_count, is_fem, fixed_node_count, total_mass (kg), dt_critical (s)."""
        handle = self._world_handle("sh_body_get_info")
        raw = sh_body_info()
        check(lib.sh_body_get_info(handle, self._cid, ctypes.byref(raw)), "sh_body_get_info")
        return record_of(BodyInfo, raw, is_fem=bool(raw.is_fem))

    @property
    def node_count(self) -> int:
        """Number of nodes (including orphans)."""
        return self.info["node_count"]

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
    ) -> None:
        """Set the material of the listed elements (a region of an FEM body). Masses are
        recomputed from the new density.

        model is "stvk", "linear", "corotational" or "neohookean"; young (Pa), poisson and
        density (kg/m^3). The C API has no per-element material getter, so a field not given
        takes the sh_fem_body_def_default value shown in the signature, not the element's
        current value. Invalid values raise softhap.Error (SH_ERR_INVALID_ARGUMENT).
        """
        arguments = dict(model=model, young=young, poisson=poisson, density=density)
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
