"""Low-level ctypes layer: finds and loads libsofthap, checks its version, mirrors the C structs
and declares the prototype of every function of include/softhap/softhap.h.

Nothing here is public API; the classes of softhap.mesh, world, body, contact and haptic wrap
it. The struct definitions below must match the header field for field
(tests/python/test_structs.py checks their sizes and offsets against a C compiler).
"""

from __future__ import annotations

import ctypes
import enum
import os
from typing import List, Mapping, Optional, Tuple
from ctypes import (
    POINTER,
    Structure,
    c_char_p,
    c_double,
    c_int,
    c_int32,
    c_int64,
    c_size_t,
    c_uint32,
    c_uint64,
    c_void_p,
)

# ------------------------------------------------------------------------------------------------
# Version this package was written for (SH_VERSION of include/softhap/softhap.h).

SH_VERSION_MAJOR = 0
SH_VERSION_MINOR = 6
SH_VERSION_PATCH = 0
SH_VERSION = SH_VERSION_MAJOR * 1000000 + SH_VERSION_MINOR * 1000 + SH_VERSION_PATCH

LIBRARY_FILE_NAME = "libsofthap.so"
LIBRARY_ENV_VAR = "SOFTHAP_LIBRARY"


def version_string(encoded: int) -> str:
    """Return "MAJOR.MINOR.PATCH" for a version in the SH_VERSION encoding."""
    encoded = int(encoded)
    return "%d.%d.%d" % (encoded // 1000000, (encoded // 1000) % 1000, encoded % 1000)


# ------------------------------------------------------------------------------------------------
# Enums (values copied from the header).


class Status(enum.IntEnum):
    """sh_status: the result code of every fallible C call."""

    SH_OK = 0
    SH_ERR_INVALID_ARGUMENT = 1
    SH_ERR_INVALID_HANDLE = 2
    SH_ERR_UNINITIALIZED_DEF = 3
    SH_ERR_OUT_OF_MEMORY = 4
    SH_ERR_IO = 5
    SH_ERR_PARSE = 6
    SH_ERR_DEGENERATE_MESH = 7
    SH_ERR_UNSTABLE = 8
    SH_ERR_UNSUPPORTED = 9
    SH_ERR_SOLVER = 10
    SH_ERR_NOT_CONVERGED = 11
    SH_ERR_CAPACITY = 12
    SH_ERR_BUSY = 13
    SH_ERR_INTERNAL = 14


class WarningKind(enum.IntEnum):
    """sh_warning: kinds of warning counters. Bit (1 << kind) marks a kind in a step report."""

    SH_WARN_UNSTABLE = 0
    SH_WARN_SUBSTEPPED = 1
    SH_WARN_INVERTED = 2
    SH_WARN_CAPACITY = 3
    SH_WARN_FORCE_CLAMPED = 4
    SH_WARN_LOCKING = 5
    SH_WARN_NOT_CONVERGED = 6


SH_WARN_COUNT = 7

#: sh_log_level: the levels of the library's log messages.
LOG_LEVELS = {"debug": 0, "info": 1, "warning": 2}
SH_LOG_COUNT = 3


class FeatureKind(enum.IntEnum):
    """sh_feature: optional components a build may include (bits of sh_build_features())."""

    SH_FEATURE_CHOLMOD = 1
    SH_FEATURE_CCD = 2


# Each enum of kinds as {name: value}, the name being the C constant's lower-case suffix
# ("rk4" for SH_INTEGRATOR_RK4), followed by its SH_*_COUNT sentinel: the number of kinds, not
# a kind. Adding a kind to the header adds its name here.
INTEGRATORS = {
    "forward_euler": 0,
    "symplectic_euler": 1,
    "rk2": 2,
    "rk4": 3,
    "implicit_euler": 4,
}
SH_INTEGRATOR_COUNT = len(INTEGRATORS)

LINEAR_SOLVERS = {
    "default": 0,
    "cholmod": 1,
    "ldlt": 2,
    "cg": 3,
}
SH_LINEAR_SOLVER_COUNT = len(LINEAR_SOLVERS)

SH_STATIC_HISTORY = 64

UNSTABLE_POLICIES = {
    "reject": 0,
    "substep": 1,
}
SH_UNSTABLE_POLICY_COUNT = len(UNSTABLE_POLICIES)

MATERIAL_MODELS = {
    "linear": 0,
    "stvk": 1,
    "corotational": 2,
    "neohookean": 3,
}
SH_MATERIAL_COUNT = len(MATERIAL_MODELS)

SPRING_LAWS = {
    "linear": 0,
    "cubic": 1,
    "hyperbolic": 2,
    "table": 3,
}
SH_SPRING_LAW_COUNT = len(SPRING_LAWS)

SHAPE_KINDS = {
    "sphere": 0,
    "capsule": 1,
    "box": 2,
    "convex": 3,
    "plane": 4,
}
SH_SHAPE_COUNT = len(SHAPE_KINDS)

CUT_CRITERIA = {
    "geometric": 0,
    "physical": 1,
}
SH_CUT_CRITERION_COUNT = len(CUT_CRITERIA)

# ------------------------------------------------------------------------------------------------
# Structs. Enums are C ints; opaque handles are void pointers. The ids are distinct one-field
# structs, as in C, so that ctypes refuses one kind of id where another is expected.


class sh_body_id(Structure):
    """Mirror of struct sh_body_id (value 0 is the null id)."""

    _fields_ = [("value", c_uint64)]


class sh_tool_id(Structure):
    """Mirror of struct sh_tool_id (value 0 is the null id)."""

    _fields_ = [("value", c_uint64)]


class sh_obstacle_id(Structure):
    """Mirror of struct sh_obstacle_id (value 0 is the null id)."""

    _fields_ = [("value", c_uint64)]


class sh_mesh_info(Structure):
    """Mirror of struct sh_mesh_info."""

    _fields_ = [
        ("node_count", c_int32),
        ("tet_count", c_int32),
        ("surface_triangle_count", c_int32),
        ("edge_count", c_int32),
        ("orphan_node_count", c_int32),
        ("reoriented_tet_count", c_int32),
        ("skipped_element_count", c_int32),
        ("bounds_min", c_double * 3),
        ("bounds_max", c_double * 3),
        ("volume", c_double),
    ]


class sh_world_def(Structure):
    """Mirror of struct sh_world_def."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("gravity", c_double * 3),
        ("error_estimate", c_int32),
    ]


class sh_step_report(Structure):
    """Mirror of struct sh_step_report."""

    _fields_ = [
        ("wall_seconds", c_double),
        ("substeps", c_int32),
        ("dt_critical", c_double),
        ("kinetic_energy", c_double),
        ("elastic_energy", c_double),
        ("potential_energy", c_double),
        ("warnings", c_uint32),
        ("unstable_body_count", c_int32),
        ("newton_iterations", c_int32),
        ("linear_iterations", c_int32),
        ("newton_residual", c_double),
        ("factorize_seconds", c_double),
        ("solve_seconds", c_double),
        ("factorizations", c_int32),
        ("error_estimate", c_double),
        ("error_estimate_seconds", c_double),
        ("contact_count", c_int32),
        ("collision_seconds", c_double),
        ("contact_substeps", c_int32),
        ("cut_faces", c_int32),
        ("topology_seconds", c_double),
        ("springs_broken", c_int32),
    ]


class sh_implicit_settings(Structure):
    """Mirror of struct sh_implicit_settings."""

    _fields_ = [
        ("linear_solver", c_int),
        ("newton_max_iterations", c_int32),
        ("newton_tolerance", c_double),
        ("cg_tolerance", c_double),
        ("cg_max_iterations", c_int32),
        ("factor_reuse", c_double),
        ("max_substeps", c_int32),
    ]


class sh_material(Structure):
    """Mirror of struct sh_material."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("model", c_int),
        ("young", c_double),
        ("poisson", c_double),
        ("density", c_double),
        ("toughness", c_double),
    ]


class sh_fem_body_def(Structure):
    """Mirror of struct sh_fem_body_def."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("mesh", c_void_p),
        ("material", sh_material),
        ("integrator", c_int),
        ("on_unstable", c_int),
        ("damping_mass", c_double),
        ("damping_stiffness", c_double),
        ("runaway_speed", c_double),
        ("implicit", sh_implicit_settings),
    ]


class sh_spring_params(Structure):
    """Mirror of struct sh_spring_params."""

    _fields_ = [
        ("law", c_int),
        ("stiffness", c_double),
        ("damping", c_double),
        ("lambda1", c_double),
        ("lambda2", c_double),
        ("a", c_double),
        ("b", c_double),
        ("table", POINTER(c_double)),
        ("table_rows", c_int32),
        ("break_strain", c_double),
    ]


class sh_spring_body_def(Structure):
    """Mirror of struct sh_spring_body_def."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("nodes", POINTER(c_double)),
        ("node_count", c_int32),
        ("springs", POINTER(c_int32)),
        ("spring_count", c_int32),
        ("mesh", c_void_p),
        ("params", sh_spring_params),
        ("node_mass", c_double),
        ("node_masses", POINTER(c_double)),
        ("integrator", c_int),
        ("on_unstable", c_int),
        ("damping_mass", c_double),
        ("runaway_speed", c_double),
        ("implicit", sh_implicit_settings),
    ]


class sh_body_info(Structure):
    """Mirror of struct sh_body_info."""

    _fields_ = [
        ("node_count", c_int32),
        ("element_count", c_int32),
        ("is_fem", c_int32),
        ("fixed_node_count", c_int32),
        ("total_mass", c_double),
        ("dt_critical", c_double),
        ("surface_triangle_count", c_int32),
        ("reserved", c_int32),
        ("topology_version", c_uint64),
    ]


class sh_cut_report(Structure):
    """Mirror of struct sh_cut_report."""

    _fields_ = [
        ("faces_separated", c_int32),
        ("nodes_added", c_int32),
        ("tets_added", c_int32),
        ("nodes_moved", c_int32),
        ("min_quality", c_double),
        ("seconds", c_double),
        ("springs_cut", c_int32),
        ("reserved", c_int32),
    ]


class sh_cut_def(Structure):
    """Mirror of struct sh_cut_def."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("criterion", c_int32),
        ("edge", (c_double * 3) * 2),
        ("sharpness", c_double),
        ("resolution", c_double),
    ]


class sh_static_def(Structure):
    """Mirror of struct sh_static_def."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("tolerance", c_double),
        ("max_iterations", c_int32),
        ("load_steps", c_int32),
        ("linear_solver", c_int),
    ]


class sh_static_report(Structure):
    """Mirror of struct sh_static_report."""

    _fields_ = [
        ("iterations", c_int32),
        ("load_steps", c_int32),
        ("converged", c_int32),
        ("history_count", c_int32),
        ("residual", c_double),
        ("residual_history", c_double * SH_STATIC_HISTORY),
        ("wall_seconds", c_double),
    ]


class sh_shape(Structure):
    """Mirror of struct sh_shape."""

    _fields_ = [
        ("kind", c_int),
        ("radius", c_double),
        ("half_length", c_double),
        ("half_extents", c_double * 3),
        ("points", POINTER(c_double)),
        ("point_count", c_int32),
        ("normal", c_double * 3),
    ]


class sh_contact_params(Structure):
    """Mirror of struct sh_contact_params."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("stiffness", c_double),
        ("exponent", c_double),
        ("damping", c_double),
        ("static_friction", c_double),
        ("dynamic_friction", c_double),
        ("slip_velocity", c_double),
        ("capacity", c_int32),
    ]


class sh_collider_def(Structure):
    """Mirror of struct sh_collider_def."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("shape", sh_shape),
        ("position", c_double * 3),
        ("orientation", c_double * 4),
        ("contact", sh_contact_params),
    ]


class sh_contact_state(Structure):
    """Mirror of struct sh_contact_state."""

    _fields_ = [
        ("force", c_double * 3),
        ("torque", c_double * 3),
        ("contact_count", c_int32),
        ("max_depth", c_double),
        ("penetration_volume", c_double),
    ]


class sh_haptic_def(Structure):
    """Mirror of struct sh_haptic_def."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("tool", sh_tool_id),
        ("capacity_tets", c_int32),
        ("capacity_nodes", c_int32),
        ("radius", c_double),
        ("rings", c_int32),
        ("dt", c_double),
        ("max_force", c_double),
        ("max_force_rate", c_double),
        ("ramp_time", c_double),
        ("stale_after", c_double),
    ]


class sh_haptic_output(Structure):
    """Mirror of struct sh_haptic_output."""

    _fields_ = [
        ("force", c_double * 3),
        ("torque", c_double * 3),
        ("contact", c_int32),
        ("buffer_tets", c_int32),
        ("buffer_nodes", c_int32),
        ("substeps", c_int32),
        ("data_age", c_double),
        ("faults", c_uint32),
        ("warnings", c_uint32),
        ("raw_force", c_double * 3),
    ]


class HapticFault(enum.IntFlag):
    """sh_haptic_fault: bits of a haptic step's faults (why the force is held or ramping out)."""

    SH_HAPTIC_FAULT_POSE = 1
    SH_HAPTIC_FAULT_DT = 2
    SH_HAPTIC_FAULT_UNSTABLE = 4
    SH_HAPTIC_FAULT_STALE = 8
    SH_HAPTIC_FAULT_NO_TOOL = 16


# Every struct the header declares that the bindings use, by C name (for the layout test).
class sh_device_mapping(Structure):
    """Mirror of struct sh_device_mapping."""

    _fields_ = [
        ("internal_init", c_uint32),
        ("scale", c_double),
        ("base_position", c_double * 3),
        ("base_orientation", c_double * 4),
        ("tool_offset", c_double * 3),
        ("force_scale", c_double),
    ]


STRUCTS = {
    "sh_mesh_info": sh_mesh_info,
    "sh_world_def": sh_world_def,
    "sh_step_report": sh_step_report,
    "sh_material": sh_material,
    "sh_fem_body_def": sh_fem_body_def,
    "sh_spring_params": sh_spring_params,
    "sh_spring_body_def": sh_spring_body_def,
    "sh_body_info": sh_body_info,
    "sh_cut_report": sh_cut_report,
    "sh_implicit_settings": sh_implicit_settings,
    "sh_static_def": sh_static_def,
    "sh_static_report": sh_static_report,
    "sh_shape": sh_shape,
    "sh_contact_params": sh_contact_params,
    "sh_collider_def": sh_collider_def,
    "sh_contact_state": sh_contact_state,
    "sh_haptic_def": sh_haptic_def,
    "sh_haptic_output": sh_haptic_output,
    "sh_device_mapping": sh_device_mapping,
}

# ------------------------------------------------------------------------------------------------
# Function prototypes: name -> (restype, argtypes).

_status = c_int
_handle = c_void_p
_pd = POINTER(c_double)
_pi = POINTER(c_int32)

PROTOTYPES = {
    # version, status, errors, memory
    "sh_version": (c_int32, []),
    "sh_build_features": (c_uint32, []),
    "sh_status_string": (c_char_p, [c_int]),
    "sh_last_error_message": (c_char_p, []),
    "sh_set_allocator": (_status, [c_void_p]),
    # meshes
    "sh_mesh_create": (_status, [_pd, c_int32, _pi, c_int32, POINTER(_handle)]),
    "sh_mesh_load": (_status, [c_char_p, POINTER(_handle)]),
    "sh_mesh_transform": (_status, [_handle, c_double, _pd, POINTER(_handle)]),
    "sh_mesh_destroy": (_status, [_handle]),
    "sh_mesh_get_info": (_status, [_handle, POINTER(sh_mesh_info)]),
    "sh_mesh_get_nodes": (_status, [_handle, _pd, c_int32]),
    "sh_mesh_get_tets": (_status, [_handle, _pi, c_int32]),
    "sh_mesh_get_surface_triangles": (_status, [_handle, _pi, c_int32]),
    "sh_mesh_get_edges": (_status, [_handle, _pi, c_int32]),
    "sh_mesh_write_vtu": (_status, [_handle, c_char_p]),
    # world
    "sh_world_def_default": (None, [POINTER(sh_world_def)]),
    "sh_world_create": (_status, [POINTER(sh_world_def), POINTER(_handle)]),
    "sh_world_destroy": (_status, [_handle]),
    "sh_world_set_gravity": (_status, [_handle, _pd]),
    "sh_world_get_warnings": (_status, [_handle, POINTER(c_uint64)]),
    "sh_world_step": (_status, [_handle, c_double, POINTER(sh_step_report)]),
    # FEM bodies
    "sh_material_default": (None, [POINTER(sh_material)]),
    "sh_fem_body_def_default": (None, [POINTER(sh_fem_body_def)]),
    "sh_fem_body_create": (_status, [_handle, POINTER(sh_fem_body_def), POINTER(sh_body_id)]),
    "sh_body_set_material": (_status, [_handle, sh_body_id, _pi, c_int32, POINTER(sh_material)]),
    # spring bodies
    "sh_spring_body_def_default": (None, [POINTER(sh_spring_body_def)]),
    "sh_spring_body_create": (
        _status,
        [_handle, POINTER(sh_spring_body_def), POINTER(sh_body_id)],
    ),
    # bodies
    "sh_body_destroy": (_status, [_handle, sh_body_id]),
    "sh_body_is_valid": (c_int32, [_handle, sh_body_id]),
    "sh_body_get_info": (_status, [_handle, sh_body_id, POINTER(sh_body_info)]),
    "sh_body_get_positions": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_set_positions": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_get_velocities": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_set_velocities": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_get_masses": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_fix_nodes": (_status, [_handle, sh_body_id, _pi, c_int32]),
    "sh_body_release_nodes": (_status, [_handle, sh_body_id, _pi, c_int32]),
    "sh_body_prescribe_positions": (_status, [_handle, sh_body_id, _pi, _pd, c_int32]),
    "sh_body_set_external_forces": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_set_node_damping": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_get_elastic_forces": (_status, [_handle, sh_body_id, _pd, c_int32]),
    "sh_body_get_elastic_energy": (_status, [_handle, sh_body_id, _pd]),
    "sh_body_write_vtu": (_status, [_handle, sh_body_id, c_char_p]),
    # cutting and topology
    "sh_body_cut": (_status, [_handle, sh_body_id, _pd, c_int32, POINTER(sh_cut_report)]),
    "sh_body_get_tets": (_status, [_handle, sh_body_id, _pi, c_int32]),
    "sh_body_get_springs": (_status, [_handle, sh_body_id, _pi, c_int32]),
    "sh_body_get_surface_triangles": (_status, [_handle, sh_body_id, _pi, c_int32]),
    "sh_body_get_node_parents": (_status, [_handle, sh_body_id, _pi, c_int32]),
    # tools, obstacles and contact
    "sh_contact_params_default": (None, [POINTER(sh_contact_params)]),
    "sh_collider_def_default": (None, [POINTER(sh_collider_def)]),
    "sh_tool_create": (_status, [_handle, POINTER(sh_collider_def), POINTER(sh_tool_id)]),
    "sh_tool_destroy": (_status, [_handle, sh_tool_id]),
    "sh_tool_is_valid": (c_int32, [_handle, sh_tool_id]),
    "sh_tool_set_pose": (_status, [_handle, sh_tool_id, _pd, _pd]),
    "sh_tool_get_pose": (_status, [_handle, sh_tool_id, _pd, _pd]),
    "sh_tool_set_velocity": (_status, [_handle, sh_tool_id, _pd, _pd]),
    "sh_cut_def_default": (None, [POINTER(sh_cut_def)]),
    "sh_tool_set_cutting": (_status, [_handle, sh_tool_id, POINTER(sh_cut_def)]),
    "sh_tool_get_contact": (_status, [_handle, sh_tool_id, POINTER(sh_contact_state)]),
    "sh_tool_get_wrench": (_status, [_handle, sh_tool_id, _pd, _pd]),
    "sh_haptic_def_default": (None, [POINTER(sh_haptic_def)]),
    "sh_haptic_memory_bytes": (_status, [POINTER(sh_haptic_def), POINTER(c_size_t)]),
    "sh_haptic_create": (_status, [_handle, POINTER(sh_haptic_def), POINTER(_handle)]),
    "sh_haptic_destroy": (_status, [_handle]),
    "sh_haptic_step": (_status, [_handle, _pd, _pd, c_double, POINTER(sh_haptic_output)]),
    "sh_haptic_get_warnings": (_status, [_handle, POINTER(c_uint64)]),
    "sh_set_log_callback": (_status, [c_void_p, c_void_p]),
    # device mapping
    "sh_device_mapping_default": (None, [POINTER(sh_device_mapping)]),
    "sh_device_mapping_check": (_status, [POINTER(sh_device_mapping)]),
    "sh_device_to_world": (_status, [POINTER(sh_device_mapping), _pd, _pd, _pd, _pd]),
    "sh_world_to_device": (_status, [POINTER(sh_device_mapping), _pd, _pd, _pd, _pd]),
    "sh_device_force": (_status, [POINTER(sh_device_mapping), _pd, _pd, _pd, _pd]),
    "sh_obstacle_create": (
        _status,
        [_handle, POINTER(sh_collider_def), POINTER(sh_obstacle_id)],
    ),
    "sh_obstacle_destroy": (_status, [_handle, sh_obstacle_id]),
    "sh_obstacle_is_valid": (c_int32, [_handle, sh_obstacle_id]),
    "sh_obstacle_get_contact": (_status, [_handle, sh_obstacle_id, POINTER(sh_contact_state)]),
    "sh_world_set_body_contact": (
        _status,
        [_handle, sh_body_id, sh_body_id, POINTER(sh_contact_params)],
    ),
    # static equilibrium
    "sh_static_def_default": (None, [POINTER(sh_static_def)]),
    "sh_world_solve_static": (
        _status,
        [_handle, POINTER(sh_static_def), POINTER(sh_static_report)],
    ),
}

# ------------------------------------------------------------------------------------------------
# Finding and loading the library.

PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))
# bindings/python/softhap -> repository root
REPO_DIR = os.path.dirname(os.path.dirname(os.path.dirname(PACKAGE_DIR)))


def library_candidates(
    environ: Optional[Mapping[str, str]] = None,
    package_dir: Optional[str] = None,
    repo_dir: Optional[str] = None,
) -> List[Tuple[str, str]]:
    """Return the list of (path, origin) places where the library is looked for, in order.

    1. the environment variable SOFTHAP_LIBRARY, if set (then it is the only candidate);
    2. libsofthap.so next to the package;
    3. <repo>/build/libsofthap.so (a CMake build tree of this checkout).
    """
    environ = os.environ if environ is None else environ
    package_dir = PACKAGE_DIR if package_dir is None else package_dir
    repo_dir = REPO_DIR if repo_dir is None else repo_dir
    explicit = environ.get(LIBRARY_ENV_VAR)
    if explicit:
        return [(explicit, "$" + LIBRARY_ENV_VAR)]
    return [
        (os.path.join(package_dir, LIBRARY_FILE_NAME), "next to the package"),
        (os.path.join(repo_dir, "build", LIBRARY_FILE_NAME), "the build tree"),
    ]


def find_library(
    environ: Optional[Mapping[str, str]] = None,
    package_dir: Optional[str] = None,
    repo_dir: Optional[str] = None,
) -> str:
    """Return the path of the libsofthap.so to load, or raise ImportError saying where it looked.

    If SOFTHAP_LIBRARY is set it must name an existing file: it is never silently ignored.
    """
    candidates = library_candidates(environ, package_dir, repo_dir)
    for path, _origin in candidates:
        if os.path.isfile(path):
            return path
    tried = "; ".join("%s (%s)" % (path, origin) for path, origin in candidates)
    raise ImportError(
        "softhap: cannot find the softhap C library. Looked for: %s. Build it with "
        "`cmake -S . -B build && cmake --build build`, or set %s to the path of %s."
        % (tried, LIBRARY_ENV_VAR, LIBRARY_FILE_NAME)
    )


def load_library(path: Optional[str] = None, expected_version: Optional[int] = None) -> ctypes.CDLL:
    """Load libsofthap from path (default: find_library()), check its version, declare prototypes.

    Raises ImportError if the file cannot be loaded, if sh_version() differs from the
    SH_VERSION this package was written for, or if a function of the header is missing.
    """
    if path is None:
        path = find_library()
    if expected_version is None:
        expected_version = SH_VERSION
    try:
        lib = ctypes.CDLL(path)
    except OSError as exc:
        raise ImportError("softhap: cannot load the C library %r: %s" % (path, exc)) from exc

    try:
        sh_version = lib.sh_version
    except AttributeError:
        raise ImportError(
            "softhap: %r does not export sh_version(); is it a softhap library?" % path
        ) from None
    sh_version.restype = c_int32
    sh_version.argtypes = []
    found = int(sh_version())
    if found != expected_version:
        raise ImportError(
            "softhap: version mismatch: the C library %r is version %s (sh_version() = %d) but "
            "this Python package was written for version %s (SH_VERSION = %d). Rebuild the "
            "library from the same checkout as the bindings, or point %s at a matching one."
            % (
                path,
                version_string(found),
                found,
                version_string(expected_version),
                expected_version,
                LIBRARY_ENV_VAR,
            )
        )

    missing = []
    for name, (restype, argtypes) in PROTOTYPES.items():
        try:
            function = getattr(lib, name)
        except AttributeError:
            missing.append(name)
            continue
        function.restype = restype
        function.argtypes = argtypes
    if missing:
        raise ImportError(
            "softhap: the C library %r (version %s) does not export: %s"
            % (path, version_string(found), ", ".join(missing))
        )
    lib.softhap_path = path  # type: ignore[attr-defined]
    return lib
