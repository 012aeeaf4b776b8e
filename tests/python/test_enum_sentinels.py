"""Every enum of kinds in include/softhap/softhap.h numbers its kinds 0, 1, ... and ends with an
SH_*_COUNT sentinel equal to their number, and the Python mirror lists the same names and
values. Read from the header's text, so that it holds without a C compiler (test_structs.py
checks the values against one)."""

import importlib.util
import re

import pytest

from conftest import BINDINGS_DIR, INCLUDE_DIR

# Enums whose values are not kinds: bit masks (sh_feature, sh_haptic_fault) and the result
# codes (sh_status), which no table is indexed by.
NOT_KINDS = {"sh_feature", "sh_haptic_fault", "sh_status"}


def _load_lib_module():
    spec = importlib.util.spec_from_file_location("softhap_lib_enums_only", BINDINGS_DIR / "softhap" / "_lib.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_lib = _load_lib_module()


def _header_enums():
    """{enum type name: [(constant, value), ...] in declaration order}."""
    text = (INCLUDE_DIR / "softhap" / "softhap.h").read_text()
    enums = {}
    for body, name in re.findall(r"typedef enum \w+ \{(.*?)\}\s*(\w+);", text, flags=re.S):
        constants = re.findall(r"^\s*(SH_[A-Z0-9_]+)\s*=\s*(\d+)", body, flags=re.M)
        enums[name] = [(constant, int(value)) for constant, value in constants]
    return enums


ENUMS = _header_enums()
KIND_ENUMS = sorted(set(ENUMS) - NOT_KINDS)

# The Python mirror of each enum of kinds: (prefix of its constants, {name: value}).
MIRRORS = {
    "sh_warning": ("SH_WARN_", {member.name[len("SH_WARN_"):].lower(): int(member) for member in _lib.WarningKind}),
    "sh_integrator": ("SH_INTEGRATOR_", _lib.INTEGRATORS),
    "sh_linear_solver": ("SH_LINEAR_SOLVER_", _lib.LINEAR_SOLVERS),
    "sh_unstable_policy": ("SH_UNSTABLE_", _lib.UNSTABLE_POLICIES),
    "sh_material_model": ("SH_MATERIAL_", _lib.MATERIAL_MODELS),
    "sh_spring_law": ("SH_SPRING_", _lib.SPRING_LAWS),
    "sh_shape_kind": ("SH_SHAPE_", _lib.SHAPE_KINDS),
    "sh_cut_criterion": ("SH_CUT_", _lib.CUT_CRITERIA),
    "sh_log_level": ("SH_LOG_", _lib.LOG_LEVELS),
}


def test_header_enums_are_found():
    assert "sh_material_model" in ENUMS and "sh_shape_kind" in ENUMS
    assert all(ENUMS.values())


@pytest.mark.parametrize("enum", KIND_ENUMS)
def test_kinds_end_with_their_count(enum):
    *kinds, (sentinel, count) = ENUMS[enum]
    assert sentinel.endswith("_COUNT"), "%s must end with an SH_*_COUNT sentinel" % enum
    assert [value for _name, value in kinds] == list(range(len(kinds)))
    assert count == len(kinds)
    assert not any(name.endswith("_COUNT") for name, _value in kinds)


def test_every_enum_of_kinds_has_a_mirror():
    assert set(MIRRORS) == set(KIND_ENUMS)


@pytest.mark.parametrize("enum", KIND_ENUMS)
def test_mirror_lists_the_kinds_and_their_count(enum):
    prefix, mirror = MIRRORS[enum]
    *kinds, (sentinel, count) = ENUMS[enum]
    assert {prefix + name.upper(): value for name, value in mirror.items()} == dict(kinds)
    assert getattr(_lib, sentinel) == count
