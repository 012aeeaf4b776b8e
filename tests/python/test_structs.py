"""The ctypes structs mirror the C structs exactly: every field's offset and every struct's size
are compared with what the C compiler computes from include/softhap/softhap.h."""

import ctypes
import importlib.util
import re
import subprocess

import pytest

from conftest import BINDINGS_DIR, INCLUDE_DIR, compile_c


def _load_lib_module():
    # softhap/_lib.py on its own (it loads no library at import), so that the layout is checked
    # even when libsofthap cannot be built or loaded.
    spec = importlib.util.spec_from_file_location(
        "softhap_lib_layout_only", BINDINGS_DIR / "softhap" / "_lib.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_lib = _load_lib_module()


def _layout_program():
    lines = [
        "#include <stddef.h>",
        "#include <stdio.h>",
        '#include "softhap/softhap.h"',
        "int main(void) {",
    ]
    for name, struct in _lib.STRUCTS.items():
        lines.append('    printf("%s sizeof %%zu\\n", sizeof(%s));' % (name, name))
        for field, _type in struct._fields_:
            lines.append(
                '    printf("%s %s %%zu\\n", offsetof(%s, %s));' % (name, field, name, field)
            )
    lines.append("    return 0;")
    lines.append("}")
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def c_layout(cc, tmp_path_factory):
    """{(struct, field or "sizeof"): bytes} as the C compiler lays the structs out."""
    workdir = tmp_path_factory.mktemp("layout")
    program = compile_c(cc, _layout_program(), workdir / "layout")
    output = subprocess.run([str(program)], capture_output=True, text=True, check=True).stdout
    layout = {}
    for line in output.splitlines():
        struct, field, value = line.split()
        layout[(struct, field)] = int(value)
    return layout


@pytest.mark.parametrize("name", sorted(_lib.STRUCTS))
def test_struct_size_matches_c(c_layout, name):
    assert ctypes.sizeof(_lib.STRUCTS[name]) == c_layout[(name, "sizeof")]


@pytest.mark.parametrize("name", sorted(_lib.STRUCTS))
def test_field_offsets_match_c(c_layout, name):
    struct = _lib.STRUCTS[name]
    for field, _type in struct._fields_:
        assert getattr(struct, field).offset == c_layout[(name, field)], field


def test_sizes_computed_by_hand():
    # Independent of any compiler: the x86-64/aarch64 SysV layout worked out from the header.
    assert ctypes.sizeof(_lib.sh_world_def) == 40  # u32, pad 4, 3 doubles, i32, pad 4
    assert ctypes.sizeof(_lib.sh_step_report) == 152  # ... 88, i32, pad 4, 2 doubles, i32, pad 4,
    # double, i32, i32, double, i32, pad 4
    assert ctypes.sizeof(_lib.sh_cut_def) == 72  # u32, i32, 6 doubles, 2 doubles
    assert ctypes.sizeof(_lib.sh_mesh_info) == 88  # 7 int32, pad 4, 7 doubles
    assert ctypes.sizeof(_lib.sh_material) == 40  # u32, int, 4 doubles
    assert ctypes.sizeof(_lib.sh_fem_body_def) == 136  # 88 + sh_implicit_settings
    assert ctypes.sizeof(_lib.sh_spring_params) == 80  # int, pad 4, 6 doubles, pointer, i32, pad 4, double
    assert ctypes.sizeof(_lib.sh_spring_body_def) == 216  # 168 + sh_implicit_settings
    assert ctypes.sizeof(_lib.sh_body_info) == 48  # 4 int32, 2 doubles, 2 int32, uint64
    assert ctypes.sizeof(_lib.sh_cut_report) == 40  # 4 int32, 2 doubles, 2 int32
    assert ctypes.sizeof(_lib.sh_implicit_settings) == 48  # i32 x2, 2 doubles, i32, pad 4, double, i32, pad 4
    assert ctypes.sizeof(_lib.sh_static_def) == 32
    assert ctypes.sizeof(_lib.sh_static_report) == 16 + 8 + 64 * 8 + 8
    assert _lib.sh_spring_body_def.params.offset == 48
    assert _lib.sh_step_report.warnings.offset == 48


def test_every_header_function_is_declared():
    # Every SH_API function of the header has a prototype in the bindings (and nothing else).
    text = (INCLUDE_DIR / "softhap" / "softhap.h").read_text()
    declared = set(re.findall(r"SH_API\s+[^;(]*?\b(sh_\w+)\s*\(", text))
    assert declared == set(_lib.PROTOTYPES)


def _python_constants():
    """{C name: value} of every enum constant and macro the bindings mirror."""
    constants = {"SH_VERSION": _lib.SH_VERSION, "SH_STATIC_HISTORY": _lib.SH_STATIC_HISTORY}
    constants.update({name: value for name, value in vars(_lib).items() if re.fullmatch(r"SH_\w+_COUNT", name)})
    for enum_class in (_lib.Status, _lib.WarningKind, _lib.FeatureKind, _lib.HapticFault):
        constants.update({member.name: int(member) for member in enum_class})
    for prefix, table in [
        ("SH_INTEGRATOR_", _lib.INTEGRATORS),
        ("SH_UNSTABLE_", _lib.UNSTABLE_POLICIES),
        ("SH_MATERIAL_", _lib.MATERIAL_MODELS),
        ("SH_SPRING_", _lib.SPRING_LAWS),
        ("SH_LINEAR_SOLVER_", _lib.LINEAR_SOLVERS),
        ("SH_SHAPE_", _lib.SHAPE_KINDS),
        ("SH_CUT_", _lib.CUT_CRITERIA),
        ("SH_LOG_", _lib.LOG_LEVELS),
    ]:
        constants.update({prefix + name.upper(): value for name, value in table.items()})
    return constants


def test_constants_match_c(cc, tmp_path):
    constants = _python_constants()
    lines = ["#include <stdio.h>", '#include "softhap/softhap.h"', "int main(void) {"]
    for name in constants:
        lines.append('    printf("%s %%lld\\n", (long long)(%s));' % (name, name))
    lines += ["    return 0;", "}"]
    program = compile_c(cc, "\n".join(lines) + "\n", tmp_path / "constants")
    output = subprocess.run([str(program)], capture_output=True, text=True, check=True).stdout
    from_c = {name: int(value) for name, value in (line.split() for line in output.splitlines())}
    assert from_c == constants


def test_every_header_enum_constant_is_mirrored():
    text = (INCLUDE_DIR / "softhap" / "softhap.h").read_text()
    declared = set()
    for body in re.findall(r"typedef enum \w+ \{(.*?)\}", text, flags=re.S):
        declared.update(re.findall(r"^\s*(SH_[A-Z0-9_]+)\s*=", body, flags=re.M))
    assert declared == set(_python_constants()) - {"SH_VERSION", "SH_STATIC_HISTORY"}
