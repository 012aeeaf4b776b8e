"""Keyword arguments turned into the C definition structs: materials, body options, spring
bodies, contact params, collider defs and static-solve settings. Not public API: World and Body
call these with their methods' arguments.

Each struct starts from its *_def_default (which also marks it initialised), then every field
named by a keyword is overwritten with the keyword's value. The methods' signatures show the C
defaults themselves (tests/python/test_defaults.py checks them against the *_def_default
functions), so an argument left out writes the value the C default already holds.
"""

from __future__ import annotations

import ctypes
from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from . import _arrays
from ._lib import (
    INTEGRATORS,
    LINEAR_SOLVERS,
    MATERIAL_MODELS,
    SHAPE_KINDS,
    SPRING_LAWS,
    UNSTABLE_POLICIES,
    sh_collider_def,
    sh_contact_params,
    sh_fem_body_def,
    sh_material,
    sh_shape,
    sh_spring_body_def,
    sh_spring_params,
    sh_static_def,
    sh_world_def,
)
from ._loaded import lib
from .mesh import Mesh

# ------------------------------------------------------------------------------------------
# Defaults that a method must tell from a value the caller gave.
#
# Some keywords are read by some kinds only (a sphere's radius, a spring law's lambda1) or clash
# with a shorthand (friction= against static_friction=): giving one where it does not apply is
# a ValueError, even when the value given equals the default. Their defaults are marked by
# default(): a float or tuple subclass, equal to the value and printed as the value in help(),
# that given() recognises. A caller cannot pass one by accident.


class _DefaultFloat(float):
    """A float default marked by default()."""

    __slots__ = ()


class _DefaultTuple(tuple):
    """A tuple default marked by default()."""

    __slots__ = ()


_Value = TypeVar("_Value", float, Tuple[float, ...])


def default(value: _Value) -> _Value:
    """value marked as a keyword's default, so that given() tells it from a caller's value."""
    if isinstance(value, tuple):
        return _DefaultTuple(float(v) for v in value)  # type: ignore[return-value]
    return _DefaultFloat(value)  # type: ignore[return-value]


def given(value: object) -> bool:
    """True if value was passed by the caller: neither None nor a default() marked default."""
    return value is not None and not isinstance(value, (_DefaultFloat, _DefaultTuple))


# ------------------------------------------------------------------------------------------
# Field tables: for each C struct filled from keyword arguments, field name -> converter.


def choose(value: object, choices: Mapping[str, int], parameter: str) -> int:
    """Map a name such as "rk4" to its C enum value; unknown names raise ValueError."""
    if isinstance(value, str) and value in choices:
        return choices[value]
    raise ValueError(
        "%s must be one of %s, got %r" % (parameter, ", ".join(repr(c) for c in choices), value)
    )


def _choice(choices: Mapping[str, int], parameter: str) -> Callable[[object], int]:
    """Converter of a name (e.g. "rk4") to its C enum value, for fill."""
    return lambda value: choose(value, choices, parameter)


def _int32(parameter: str) -> Callable[[Any], int]:
    """Converter of an integer count, for fill."""
    return lambda value: _arrays.count(value, parameter)


Fields = Dict[str, Callable[[Any], Any]]

MATERIAL_FIELDS: Fields = {
    "model": _choice(MATERIAL_MODELS, "model"),
    "young": float,
    "poisson": float,
    "density": float,
    "toughness": float,
}
BODY_FIELDS: Fields = {  # shared by sh_fem_body_def and sh_spring_body_def
    "integrator": _choice(INTEGRATORS, "integrator"),
    "on_unstable": _choice(UNSTABLE_POLICIES, "on_unstable"),
    "damping_mass": float,
    "runaway_speed": float,
}
IMPLICIT_FIELDS: Fields = {
    "linear_solver": _choice(LINEAR_SOLVERS, "linear_solver"),
    "newton_max_iterations": _int32("newton_max_iterations"),
    "newton_tolerance": float,
    "cg_tolerance": float,
    "cg_max_iterations": _int32("cg_max_iterations"),
    "factor_reuse": float,
    "max_substeps": _int32("max_substeps"),
}
CONTACT_FIELDS: Fields = {
    "stiffness": float,
    "exponent": float,
    "damping": float,
    "static_friction": float,
    "dynamic_friction": float,
    "slip_velocity": float,
    "capacity": _int32("capacity"),
}
STATIC_FIELDS: Fields = {
    "tolerance": float,
    "max_iterations": _int32("max_iterations"),
    "load_steps": _int32("load_steps"),
    "linear_solver": _choice(LINEAR_SOLVERS, "linear_solver"),
}

# Which sh_spring_params fields each law reads (damping is read by every law).
SPRING_LAW_PARAMETERS = {
    "linear": ("stiffness", "damping"),
    "cubic": ("lambda1", "lambda2", "damping"),
    "hyperbolic": ("a", "b", "damping"),
    "table": ("table", "damping"),
}

# Which sh_shape fields each shape kind reads.
SHAPE_PARAMETERS = {
    "sphere": ("radius",),
    "capsule": ("radius", "half_length"),
    "box": ("half_extents",),
    "convex": ("points",),
    "plane": ("normal",),
}


def fill(struct: ctypes.Structure, fields: Fields, arguments: Mapping[str, Any]) -> None:
    """Set each field of struct named in fields from arguments[name] through its converter. An
    argument passed as None explicitly keeps the struct's C default, as it did when None was
    the signatures' default."""
    for name, convert in fields.items():
        value = arguments.get(name)
        if value is not None:
            setattr(struct, name, convert(value))


def _set_vector(target: ctypes.Array, value: ArrayLike, name: str) -> None:
    """Copy a vector of len(target) floats into a ctypes double array, checking its shape."""
    array = _arrays.float_array(value, name, (len(target),))
    for k in range(len(target)):
        target[k] = array[k]


# ------------------------------------------------------------------------------------------
# World and static solve.


def world_def(gravity: ArrayLike, error_estimate: bool) -> sh_world_def:
    """An sh_world_def (sh_world_def_default) with the given gravity and step doubling."""
    definition = sh_world_def()
    lib.sh_world_def_default(ctypes.byref(definition))
    _set_vector(definition.gravity, gravity, "gravity")
    definition.error_estimate = 1 if error_estimate else 0
    return definition


def static_def(arguments: Mapping[str, Any]) -> sh_static_def:
    """An sh_static_def (sh_static_def_default) with World.solve_static's keyword arguments."""
    definition = sh_static_def()
    lib.sh_static_def_default(ctypes.byref(definition))
    fill(definition, STATIC_FIELDS, arguments)
    return definition


# ------------------------------------------------------------------------------------------
# Bodies.


def material(arguments: Mapping[str, Any]) -> sh_material:
    """The material of sh_material_default with the fields named in arguments replaced."""
    result = sh_material()
    lib.sh_material_default(ctypes.byref(result))
    fill(result, MATERIAL_FIELDS, arguments)
    return result


def _set_body_options(definition: ctypes.Structure, arguments: Mapping[str, Any]) -> None:
    """Fill the options sh_fem_body_def and sh_spring_body_def share (integration and implicit
    settings) from a method's keyword arguments."""
    fill(definition, BODY_FIELDS, arguments)
    fill(definition.implicit, IMPLICIT_FIELDS, arguments)


def fem_body_def(mesh_handle: int, arguments: Mapping[str, Any]) -> sh_fem_body_def:
    """An sh_fem_body_def (sh_fem_body_def_default) of the mesh with World.add_fem_body's
    keyword arguments."""
    definition = sh_fem_body_def()
    lib.sh_fem_body_def_default(ctypes.byref(definition))
    definition.mesh = mesh_handle
    fill(definition.material, MATERIAL_FIELDS, arguments)
    if arguments.get("damping_stiffness") is not None:
        definition.damping_stiffness = float(arguments["damping_stiffness"])
    _set_body_options(definition, arguments)
    return definition


def _spring_nodes(
    definition: sh_spring_body_def, nodes: Any, springs: Optional[ArrayLike], arrays: List[Any]
) -> int:
    """Point the def at its nodes (an (n, 3) array, or a Mesh whose nodes and, with springs
    None, edges are used) and springs; return the node count."""
    if isinstance(nodes, Mesh):
        definition.mesh = nodes._require_handle("sh_spring_body_create")
        node_count = nodes.node_count
    else:
        node_array = _arrays.float_array(nodes, "nodes", (None, 3))
        arrays.append(node_array)
        definition.nodes = _arrays.double_ptr(node_array)
        definition.node_count = _arrays.count(node_array.shape[0], "node count")
        node_count = node_array.shape[0]
    if springs is not None:
        spring_array = _arrays.index_array(springs, "springs", (None, 2))
        arrays.append(spring_array)
        definition.springs = _arrays.int32_ptr(spring_array)
        definition.spring_count = _arrays.count(spring_array.shape[0], "spring count")
    return node_count


def _spring_law(
    params: sh_spring_params, law: str, arguments: Mapping[str, Any], arrays: List[Any]
) -> None:
    """Set the spring law and the parameters it reads; a parameter of another law given by
    the caller raises ValueError."""
    params.law = choose(law, SPRING_LAWS, "law")
    accepted = SPRING_LAW_PARAMETERS[law]
    for name in ("stiffness", "damping", "lambda1", "lambda2", "a", "b", "table"):
        if given(arguments.get(name)) and name not in accepted:
            raise ValueError(
                "%s= is not a parameter of the %r spring law (it takes: %s)"
                % (name, law, ", ".join(accepted))
            )
    for name in ("stiffness", "damping", "lambda1", "lambda2", "a", "b"):
        if name in accepted and arguments.get(name) is not None:
            setattr(params, name, float(arguments[name]))
    params.break_strain = float(arguments.get("break_strain", 0.0))
    table = arguments.get("table")
    if table is not None:
        table_array = _arrays.float_array(table, "table", (None, 2))
        arrays.append(table_array)
        params.table = _arrays.double_ptr(table_array)
        params.table_rows = _arrays.count(table_array.shape[0], "table rows")


def _spring_masses(
    definition: sh_spring_body_def, mass: Any, node_count: int, arrays: List[Any]
) -> None:
    """Set the mass of every node (a scalar) or of each node (an array of node_count)."""
    if mass is None:
        return
    if np.ndim(mass) == 0:
        definition.node_mass = float(mass)
    else:
        mass_array = _arrays.float_array(mass, "mass", (node_count,))
        arrays.append(mass_array)
        definition.node_masses = _arrays.double_ptr(mass_array)


def spring_body_def(
    nodes: Any,
    springs: Optional[ArrayLike],
    law: str,
    mass: Any,
    arguments: Mapping[str, Any],
) -> Tuple[sh_spring_body_def, List[Any]]:
    """An sh_spring_body_def (sh_spring_body_def_default) with World.add_spring_body's
    arguments. Returns (def, arrays): arrays must stay alive until the create call returns
    (the def points into them)."""
    definition = sh_spring_body_def()
    lib.sh_spring_body_def_default(ctypes.byref(definition))
    arrays: List[Any] = []
    node_count = _spring_nodes(definition, nodes, springs, arrays)
    _spring_law(definition.params, law, arguments, arrays)
    _spring_masses(definition, mass, node_count, arrays)
    _set_body_options(definition, arguments)
    return definition, arrays


# ------------------------------------------------------------------------------------------
# Contact and colliders.


def _contact_arguments(arguments: Mapping[str, Any]) -> Dict[str, Any]:
    """The sh_contact_params keyword arguments of a method, with the shorthand friction=mu
    turned into static_friction = dynamic_friction = mu."""
    arguments = dict(arguments)
    friction = arguments.get("friction")
    if friction is not None:
        for name in ("static_friction", "dynamic_friction"):
            if given(arguments.get(name)):
                raise ValueError(
                    "friction= sets both static_friction and dynamic_friction; give either "
                    "friction= or %s=, not both" % name
                )
            arguments[name] = friction
    return arguments


def contact_params(arguments: Mapping[str, Any]) -> sh_contact_params:
    """An sh_contact_params (sh_contact_params_default) with a method's contact keywords."""
    params = sh_contact_params()
    lib.sh_contact_params_default(ctypes.byref(params))
    fill(params, CONTACT_FIELDS, _contact_arguments(arguments))
    return params


def _set_shape(shape: sh_shape, kind: str, arguments: Mapping[str, Any], arrays: List[Any]) -> None:
    """Set the shape kind and the fields it reads; a field of another kind given by the
    caller raises ValueError."""
    shape.kind = choose(kind, SHAPE_KINDS, "kind")
    accepted = SHAPE_PARAMETERS[kind]
    for name in ("radius", "half_length", "half_extents", "points", "normal"):
        if given(arguments.get(name)) and name not in accepted:
            raise ValueError(
                "%s= is not a parameter of a %r shape (it takes: %s)"
                % (name, kind, ", ".join(p + "=" for p in accepted))
            )
    for name in ("radius", "half_length"):
        if name in accepted and arguments.get(name) is not None:
            setattr(shape, name, float(arguments[name]))
    for name in ("half_extents", "normal"):
        if name in accepted and arguments.get(name) is not None:
            _set_vector(getattr(shape, name), arguments[name], name)
    if "points" in accepted and arguments.get("points") is not None:
        points = _arrays.float_array(arguments["points"], "points", (None, 3))
        arrays.append(points)
        shape.points = _arrays.double_ptr(points)
        shape.point_count = _arrays.count(points.shape[0], "point count")


def collider_def(
    kind: str,
    arguments: Mapping[str, Any],
    position: Optional[ArrayLike],
    orientation: Optional[ArrayLike],
) -> Tuple[sh_collider_def, List[Any]]:
    """An sh_collider_def (sh_collider_def_default) of shape kind with the shape fields and
    contact law in arguments, at position and orientation. Returns (def, arrays): arrays must
    stay alive until the create call returns (the def points into them)."""
    definition = sh_collider_def()
    lib.sh_collider_def_default(ctypes.byref(definition))
    arrays: List[Any] = []
    _set_shape(definition.shape, kind, arguments, arrays)
    if position is not None:  # None keeps the C default (the origin)
        _set_vector(definition.position, position, "position")
    if orientation is not None:
        _set_vector(definition.orientation, orientation, "orientation")
    definition.contact = contact_params(arguments)
    return definition, arrays
