"""softhap.Haptic (an sh_haptic: a Volumetric Buffer Model context of one tool) and its
HapticResult.

World.add_haptic makes one. Haptic.step is the device-rate call (sh_haptic_step): it reuses
its ctypes buffers, so a Python haptic loop allocates only the small result it returns.
"""

from __future__ import annotations

import ctypes
import functools
from typing import TYPE_CHECKING, Any, Dict, FrozenSet, Iterable, Optional, Sequence, Union

import numpy as np

from ._handle import OwnedHandle
from ._lib import SH_WARN_COUNT, HapticFault, Status, WarningKind, sh_haptic_def, sh_haptic_output
from ._loaded import check, lib
from ._record import Record, warning_names

if TYPE_CHECKING:
    from .contact import Tool
    from .world import World


class HapticResult(Record):
    """What one Haptic.step rendered (sh_haptic_output): force (N) and torque (N m) to render,
    (3,) arrays in the world frame, clamped and ramped; raw_force, the buffer's force before
    that; contact (bool); buffer_tets and buffer_nodes in use; substeps; data_age (s of haptic
    time since the newest full-model data); faults (set of sh_haptic_fault names) and
    fault_bits; warnings (set of sh_warning names) and warning_bits."""


def _names(bits: int, kinds: Iterable[HapticFault]) -> FrozenSet[str]:
    return frozenset(str(kind.name) for kind in kinds if bits & int(kind))


@functools.lru_cache(maxsize=256)
def _fault_names(bits: int) -> FrozenSet[str]:
    """The sh_haptic_fault names of bits (cached: a device loop sees few distinct patterns)."""
    return _names(bits, HapticFault)


_POSE_OR_DT = int(HapticFault.SH_HAPTIC_FAULT_POSE | HapticFault.SH_HAPTIC_FAULT_DT)

# sh_haptic_output's doubles: force[3] and torque[3] from the start, raw_force[3] further on.
_DOUBLE = ctypes.sizeof(ctypes.c_double)
_RAW_FORCE_AT = sh_haptic_output.raw_force.offset // _DOUBLE
_DOUBLES = _RAW_FORCE_AT + 3


def _result(raw: sh_haptic_output) -> HapticResult:
    """The HapticResult of a filled sh_haptic_output: every field under its C name, built
    directly (a device loop calls this at up to 10 kHz; record_of's generic walk costs 7 us)."""
    doubles = np.frombuffer(raw, dtype=np.float64, count=_DOUBLES).copy()
    faults, warnings = int(raw.faults), int(raw.warnings)
    return HapticResult(
        force=doubles[0:3],
        torque=doubles[3:6],
        contact=bool(raw.contact),
        buffer_tets=raw.buffer_tets,
        buffer_nodes=raw.buffer_nodes,
        substeps=raw.substeps,
        data_age=raw.data_age,
        faults=_fault_names(faults),
        warnings=warning_names(warnings),
        raw_force=doubles[_RAW_FORCE_AT:_DOUBLES],
        fault_bits=faults,
        warning_bits=warnings,
    )


def _haptic_def(tool: Tool, options: Dict[str, Any]) -> sh_haptic_def:
    definition = sh_haptic_def()
    lib.sh_haptic_def_default(ctypes.byref(definition))
    definition.tool = tool._cid
    for name, value in options.items():
        if value is None:
            continue
        if name not in {field[0] for field in sh_haptic_def._fields_} or name in ("internal_init", "tool"):
            raise TypeError("unknown haptic option %r" % name)
        setattr(definition, name, value)
    return definition


class Haptic(OwnedHandle):
    """A haptic context: a small explicit FEM buffer around a tool's contact, stepped by step()
    at the device rate while World.step re-extracts it from the full model. It keeps its World
    and Tool alive; close() (or the end of a ``with`` block) destroys it. Once the world is
    closed, step() reports the fault SH_HAPTIC_FAULT_NO_TOOL and ramps the force out."""

    _kind = "haptic context"
    _destroy = "sh_haptic_destroy"

    def __init__(self, world: World, tool: Tool, **options: Any) -> None:
        """Use World.add_haptic."""
        self._handle = None
        definition = _haptic_def(tool, options)
        handle = ctypes.c_void_p()
        check(
            lib.sh_haptic_create(world._require_handle("sh_haptic_create"), ctypes.byref(definition), ctypes.byref(handle)),
            "sh_haptic_create",
        )
        self._handle = handle.value
        self._world = world
        self._tool = tool
        self._dt = float(definition.dt)
        out = ctypes.c_size_t()
        check(lib.sh_haptic_memory_bytes(ctypes.byref(definition), ctypes.byref(out)), "sh_haptic_memory_bytes")
        self._memory_bytes = int(out.value)
        self._position = (ctypes.c_double * 3)()
        self._orientation = (ctypes.c_double * 4)()
        self._output = sh_haptic_output()
        self._output_ref = ctypes.byref(self._output)

    def __repr__(self) -> str:
        return "<softhap.Haptic %s>" % ("closed" if self._handle is None else "tool=%#x" % self._tool.id)

    @property
    def tool(self) -> Tool:
        """The Tool the device moves."""
        return self._tool

    @property
    def memory_bytes(self) -> int:
        """Bytes of memory the context holds, fixed at creation."""
        return self._memory_bytes

    @property
    def dt(self) -> float:
        """The nominal haptic step (s) that step() uses when no dt is given."""
        return self._dt

    def step(
        self,
        position: Union[Sequence[float], np.ndarray],
        orientation: Union[Sequence[float], np.ndarray] = (1.0, 0.0, 0.0, 0.0),
        dt: Optional[float] = None,
    ) -> HapticResult:
        """Step the buffer to the device pose (position m, orientation unit quaternion
        (w, x, y, z)) over dt seconds (default: the context's dt) and return the HapticResult.
        A non-finite pose or dt is not raised: the result carries the fault (force held and
        ramping out), as the C call reports it."""
        handle = self._handle
        if handle is None:
            self._require_handle("sh_haptic_step")
        self._position[0], self._position[1], self._position[2] = position[0], position[1], position[2]
        o = self._orientation
        o[0], o[1], o[2], o[3] = orientation[0], orientation[1], orientation[2], orientation[3]
        raw = self._output
        status = lib.sh_haptic_step(handle, self._position, o, self._dt if dt is None else float(dt), self._output_ref)
        if status != Status.SH_OK and not (raw.faults & _POSE_OR_DT):
            check(status, "sh_haptic_step")
        return _result(raw)

    @property
    def warnings(self) -> Dict[str, int]:
        """The context's warning counters as a dict {"SH_WARN_FORCE_CLAMPED": count, ...}."""
        handle = self._require_handle("sh_haptic_get_warnings")
        counters = (ctypes.c_uint64 * SH_WARN_COUNT)()
        check(lib.sh_haptic_get_warnings(handle, counters), "sh_haptic_get_warnings")
        return {kind.name: int(counters[int(kind)]) for kind in WarningKind}
