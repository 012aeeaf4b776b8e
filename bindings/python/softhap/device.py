"""softhap.DeviceMapping: a haptic device's units, frame and tool offset against the world, and
the force scale (sh_device_mapping)."""

from __future__ import annotations

import ctypes
from typing import Tuple

import numpy as np
from numpy.typing import ArrayLike

from . import _arrays
from ._lib import sh_device_mapping
from ._loaded import check, lib


class DeviceMapping:
    """From a device's workspace to the world and back: a device pose (p_d, q_d) is the world
    pose p = base_position + scale R_base (p_d + R_d tool_offset), q = q_base q_d; a world
    wrench reaches the device turned into its frame and times force_scale.

        mm_y_up = softhap.DeviceMapping(scale=0.001, base_orientation=(0.7071068, 0.7071068, 0, 0))
        position, orientation = mm_y_up.to_world(device_position, device_orientation)
        device_force, device_torque = mm_y_up.force_to_device(result.force, result.torque)

    Invalid values raise softhap.Error (SH_ERR_INVALID_ARGUMENT naming the field) when made."""

    def __init__(self, scale: float = 1.0, base_position: ArrayLike = (0.0, 0.0, 0.0),
                 base_orientation: ArrayLike = (1.0, 0.0, 0.0, 0.0), tool_offset: ArrayLike = (0.0, 0.0, 0.0),
                 force_scale: float = 1.0) -> None:
        """scale: world metres per device length unit; base_position (m) and base_orientation
        (quaternion w, x, y, z): the device frame in the world; tool_offset: the tool point in
        the end-effector's frame (device units); force_scale: device force per world force."""
        self._c = sh_device_mapping()
        lib.sh_device_mapping_default(ctypes.byref(self._c))
        self._c.scale = float(scale)
        self._c.force_scale = float(force_scale)
        for field, value, n in (("base_position", base_position, 3), ("base_orientation", base_orientation, 4),
                                ("tool_offset", tool_offset, 3)):
            getattr(self._c, field)[:] = [float(v) for v in _arrays.float_array(value, field, (n,))]
        check(lib.sh_device_mapping_check(ctypes.byref(self._c)), "sh_device_mapping_check")

    def _pair(self, function: str, a: ArrayLike, b: ArrayLike, names: Tuple[str, str],
              sizes: Tuple[int, int]) -> Tuple[np.ndarray, np.ndarray]:
        """Calls function(mapping, a, b, out_a, out_b) with a and b checked as names say."""
        first = _arrays.float_array(a, names[0], (sizes[0],))
        second = _arrays.float_array(b, names[1], (sizes[1],))
        out_a, out_b = np.zeros(sizes[0]), np.zeros(sizes[1])
        check(getattr(lib, function)(ctypes.byref(self._c), _arrays.double_ptr(first), _arrays.double_ptr(second),
                                     _arrays.double_ptr(out_a), _arrays.double_ptr(out_b)), function)
        return out_a, out_b

    def to_world(self, position: ArrayLike, orientation: ArrayLike = (1.0, 0.0, 0.0, 0.0)) -> Tuple[np.ndarray, np.ndarray]:
        """The tool's world (position, orientation) for a device pose (sh_device_to_world)."""
        return self._pair("sh_device_to_world", position, orientation, ("position", "orientation"), (3, 4))

    def to_device(self, position: ArrayLike, orientation: ArrayLike = (1.0, 0.0, 0.0, 0.0)) -> Tuple[np.ndarray, np.ndarray]:
        """The device (position, orientation) that puts the tool at a world pose
        (sh_world_to_device)."""
        return self._pair("sh_world_to_device", position, orientation, ("position", "orientation"), (3, 4))

    def force_to_device(self, force: ArrayLike, torque: ArrayLike = (0.0, 0.0, 0.0)) -> Tuple[np.ndarray, np.ndarray]:
        """A world wrench on the tool as the device renders it (sh_device_force)."""
        return self._pair("sh_device_force", force, torque, ("force", "torque"), (3, 3))
