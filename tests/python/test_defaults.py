"""The keyword defaults of the Python signatures are the C library's *_def_default values.

The bindings write the defaults out in their signatures (so that help() shows them); this test
calls each *_def_default function through ctypes and compares field by field, so that the two
cannot drift apart. Every keyword default of the checked methods is compared, except those
listed in NO_DEFAULT, which are None because the C default is no usable value."""

import ctypes
import inspect

import pytest

import softhap
from softhap import _lib

World = softhap.World

# For each (method, C default function, struct): keyword -> field of the struct (a dotted path)
# and, for names of C enums, the table mapping the name to its value.
CASES = [
    (World.__init__, "sh_world_def_default", _lib.sh_world_def, {
        "gravity": "gravity",
        "error_estimate": "error_estimate",
    }),
    (World.solve_static, "sh_static_def_default", _lib.sh_static_def, {
        "tolerance": "tolerance",
        "max_iterations": "max_iterations",
        "load_steps": "load_steps",
        "linear_solver": ("linear_solver", _lib.LINEAR_SOLVERS),
    }),
]
MATERIAL = {
    "model": ("material.model", _lib.MATERIAL_MODELS),
    "young": "material.young",
    "poisson": "material.poisson",
    "density": "material.density",
    "toughness": "material.toughness",
}
BODY_OPTIONS = {
    "integrator": ("integrator", _lib.INTEGRATORS),
    "on_unstable": ("on_unstable", _lib.UNSTABLE_POLICIES),
    "damping_mass": "damping_mass",
    "runaway_speed": "runaway_speed",
    "linear_solver": ("implicit.linear_solver", _lib.LINEAR_SOLVERS),
    "newton_max_iterations": "implicit.newton_max_iterations",
    "newton_tolerance": "implicit.newton_tolerance",
    "cg_tolerance": "implicit.cg_tolerance",
    "cg_max_iterations": "implicit.cg_max_iterations",
    "factor_reuse": "implicit.factor_reuse",
    "max_substeps": "implicit.max_substeps",
}
CONTACT = {
    name: "contact." + name
    for name in ("stiffness", "exponent", "damping", "static_friction", "dynamic_friction",
                 "slip_velocity", "capacity")
}
TOOL = {
    "radius": "shape.radius",
    "half_length": "shape.half_length",
    "position": "position",
    "orientation": "orientation",
    **CONTACT,
}
CASES += [
    (World.add_fem_body, "sh_fem_body_def_default", _lib.sh_fem_body_def, {
        **MATERIAL, **BODY_OPTIONS, "damping_stiffness": "damping_stiffness",
    }),
    (World.add_spring_body, "sh_spring_body_def_default", _lib.sh_spring_body_def, {
        **BODY_OPTIONS,
        "law": ("params.law", _lib.SPRING_LAWS),
        "stiffness": "params.stiffness",
        "damping": "params.damping",
        "lambda1": "params.lambda1",
        "a": "params.a",
        "break_strain": "params.break_strain",
        "mass": "node_mass",
    }),
    (softhap.Body.set_material, "sh_fem_body_def_default", _lib.sh_fem_body_def, MATERIAL),
    (World.add_tool, "sh_collider_def_default", _lib.sh_collider_def, TOOL),
    (World.add_obstacle, "sh_collider_def_default", _lib.sh_collider_def, {
        **TOOL, "normal": "shape.normal",
    }),
    (World.set_body_contact, "sh_contact_params_default", _lib.sh_contact_params, {
        name: path[len("contact."):] for name, path in CONTACT.items()
    }),
    (World.add_haptic, "sh_haptic_def_default", _lib.sh_haptic_def, {
        name: name
        for name in ("capacity_tets", "capacity_nodes", "radius", "rings", "dt", "max_force",
                     "max_force_rate", "ramp_time", "stale_after")
    }),
]

# Keywords whose default is None, by method name, and the C default field that explains why:
# the field is 0 or NULL, which the kind that reads it rejects (so it must be given), or the
# keyword is optional input (friction= sets both frictions; springs, table and points are
# arrays).
NO_DEFAULT = {
    "add_spring_body": {"springs": None, "lambda2": "params.lambda2", "b": "params.b",
                        "table": None},
    "add_tool": {"half_extents": "shape.half_extents", "points": None, "friction": None},
    "add_obstacle": {"half_extents": "shape.half_extents", "points": None, "friction": None},
    "set_body_contact": {"friction": None},
}


def c_default(function, struct):
    """The struct filled by the C library's function (through ctypes)."""
    value = struct()
    getattr(softhap._c_library, function)(ctypes.byref(value))
    return value


def field(struct, path):
    value = struct
    for name in path.split("."):
        value = getattr(value, name)
    return tuple(value) if isinstance(value, ctypes.Array) else value


def keyword_defaults(method):
    return {
        name: parameter.default
        for name, parameter in inspect.signature(method).parameters.items()
        if parameter.default is not inspect.Parameter.empty
    }


@pytest.mark.parametrize("method, function, struct, fields", CASES,
                         ids=[case[0].__qualname__ for case in CASES])
def test_signature_defaults_are_the_c_defaults(method, function, struct, fields):
    defaults = keyword_defaults(method)
    c = c_default(function, struct)
    for name, path in fields.items():
        choices = None
        if isinstance(path, tuple):
            path, choices = path
        expected = field(c, path)
        actual = defaults[name]
        if choices is not None:
            assert choices[actual] == expected, (name, actual, expected)
        elif isinstance(expected, tuple):
            assert tuple(float(v) for v in actual) == expected, name
        else:
            assert actual == expected and type(expected)(actual) == expected, (name, actual, expected)


@pytest.mark.parametrize("method, function, struct, fields", CASES,
                         ids=[case[0].__qualname__ for case in CASES])
def test_every_keyword_default_is_checked(method, function, struct, fields):
    # A keyword added with a default is either compared above or listed in NO_DEFAULT.
    defaults = keyword_defaults(method)
    absent = NO_DEFAULT.get(method.__name__, {})
    assert {name for name, value in defaults.items() if value is None} == set(absent)
    assert {name for name, value in defaults.items() if value is not None} == set(fields)
    c = c_default(function, struct)
    for name, path in absent.items():
        if path is not None:  # no usable C default: 0 (or a zero vector), rejected by its kind
            value = field(c, path)
            assert all(v == 0.0 for v in (value if isinstance(value, tuple) else (value,))), name


def test_a_keyword_of_another_kind_is_rejected_even_at_its_default_value():
    # Defaults of keywords only some kinds read are marked, so that a caller giving one is
    # told, whatever the value.
    with softhap.World() as world:
        with pytest.raises(ValueError, match="radius"):
            world.add_tool("box", half_extents=(0.01, 0.01, 0.01), radius=0.005)
        with pytest.raises(ValueError, match="normal"):
            world.add_obstacle("sphere", normal=(0.0, 0.0, 1.0))
        with pytest.raises(ValueError, match="stiffness"):
            world.add_spring_body([[0, 0, 0], [1, 0, 0]], [[0, 1]], law="cubic", lambda2=1.0,
                                  stiffness=100.0)
        with pytest.raises(ValueError, match="static_friction"):
            world.add_tool("sphere", friction=0.3, static_friction=0.0)
        # left out, they are not given: every kind accepts the defaults it does not read
        world.add_tool("box", half_extents=(0.01, 0.01, 0.01))
        world.add_obstacle("plane", position=(0.0, 0.0, -1.0))
        world.add_spring_body([[0, 0, 0], [1, 0, 0]], [[0, 1]], law="cubic", lambda2=1.0)
