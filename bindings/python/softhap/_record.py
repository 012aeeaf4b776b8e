"""Record: a dict whose keys can also be read as attributes (report["substeps"] or
report.substeps). Used for mesh info, body info and step reports."""

from __future__ import annotations

import ctypes
import functools
from typing import Any, FrozenSet, Type, TypeVar

import numpy as np

from ._lib import WarningKind, sh_static_report, sh_step_report

_R = TypeVar("_R", bound="Record")


class Record(dict):
    """A dict of named values, also readable as attributes."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(
                "%s has no field %r (fields: %s)" % (type(self).__name__, name, ", ".join(self))
            ) from None

    def __dir__(self) -> list:
        return list(super().__dir__()) + list(self.keys())

    def __repr__(self) -> str:
        items = ", ".join("%s=%r" % item for item in self.items())
        return "%s(%s)" % (type(self).__name__, items)


def record_of(cls: Type[_R], raw: ctypes.Structure, **overrides: Any) -> _R:
    """A cls holding every field of the ctypes struct raw under its C name (arrays as tuples),
    with the values in overrides replacing or adding fields."""
    values = {}
    for name, *_ in raw._fields_:
        value = getattr(raw, name)
        values[name] = tuple(value) if isinstance(value, ctypes.Array) else value
    values.update(overrides)
    return cls(values)


class MeshInfo(Record):
    """Facts about a mesh (sh_mesh_info): node_count, tet_count, surface_triangle_count,
    edge_count, orphan_node_count, reoriented_tet_count, skipped_element_count, bounds_min,
    bounds_max (tuples, m) and volume (m^3)."""


class BodyInfo(Record):
    """Facts about a body (sh_body_info): node_count, element_count (tets or springs), is_fem
    (bool), fixed_node_count, total_mass (kg), dt_critical (s; inf if none),
    surface_triangle_count (FEM boundary triangles; 0 for mass-spring bodies), reserved (0) and
    topology_version (0 at creation; increases at every topology change, such as a cut)."""


class CutReport(Record):
    """What one Body.cut did (sh_cut_report): faces_separated (tet faces that became surface,
    once per pair that parted), nodes_added (points made on cut edges and node copies),
    tets_added (tets after minus tets before), nodes_moved (existing nodes moved onto the cut
    surface), min_quality (lowest shape quality 6 sqrt(2) V / l_rms^3 of the tets the cut made:
    1 regular, 0 flat; 1 if it made none), seconds (wall time of the cut, s), springs_cut
    (mass-spring bodies: springs the surface crossed, removed) and reserved (0)."""


class StepReport(Record):
    """What one World.step did and cost (sh_step_report).

    Fields: wall_seconds (s), substeps, dt_critical (s), kinetic_energy, elastic_energy,
    potential_energy (J), warnings (a frozenset of warning names raised in this step, e.g.
    {"SH_WARN_SUBSTEPPED"}), warning_bits (the raw bit mask, bit 1 << sh_warning),
    unstable_body_count, and for implicit bodies newton_iterations, linear_iterations,
    newton_residual, factorize_seconds and solve_seconds (s) and factorizations (0 when every
    solve reused a kept factorisation); error_estimate (m: step doubling, with
    World(error_estimate=True), else -1) and error_estimate_seconds.
    """


class StaticReport(Record):
    """What World.solve_static did (sh_static_report): iterations, load_steps, converged
    (bool), residual (final largest relative residual), residual_history (array of the relative
    residual after each iteration) and wall_seconds (s)."""


@functools.lru_cache(maxsize=256)
def warning_names(bits: int) -> FrozenSet[str]:
    """The names of the sh_warning kinds whose bit (1 << kind) is set in bits (cached: a step
    loop sees few distinct patterns)."""
    return frozenset(kind.name for kind in WarningKind if bits & (1 << int(kind)))


def step_report(raw: sh_step_report) -> StepReport:
    """The StepReport of a filled sh_step_report."""
    return record_of(StepReport, raw, warnings=warning_names(raw.warnings), warning_bits=int(raw.warnings))


def static_report(raw: sh_static_report) -> StaticReport:
    """The StaticReport of a filled sh_static_report (its history cut to history_count)."""
    count = max(0, min(int(raw.history_count), len(raw.residual_history)))
    return StaticReport(
        iterations=raw.iterations,
        load_steps=raw.load_steps,
        converged=bool(raw.converged),
        residual=raw.residual,
        residual_history=np.array(raw.residual_history[:count], dtype=np.float64),
        wall_seconds=raw.wall_seconds,
    )
