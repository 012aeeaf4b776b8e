"""Body, tool and obstacle ids are distinct C types: passing one kind where another is expected
does not compile (checked with the C compiler on the public header), while the right kind does.
Also checks that the header compiles as C++ with the same incompatibility."""

import shutil
import subprocess

import pytest

from conftest import INCLUDE_DIR

PRELUDE = """
#include <softhap/softhap.h>
int use(sh_world* world, sh_body_id body, sh_tool_id tool, sh_obstacle_id obstacle) {
    sh_body_info info;
    sh_contact_state state;
    (void)body; (void)tool; (void)obstacle; (void)info; (void)state;
    return (int)(%s);
}
"""

RIGHT = [
    "sh_body_get_info(world, body, &info)",
    "sh_tool_get_contact(world, tool, &state)",
    "sh_obstacle_get_contact(world, obstacle, &state)",
    "sh_body_destroy(world, body)",
]

WRONG = [
    "sh_body_get_info(world, tool, &info)",
    "sh_body_destroy(world, obstacle)",
    "sh_tool_get_contact(world, obstacle, &state)",
    "sh_obstacle_get_contact(world, tool, &state)",
    "sh_tool_destroy(world, body)",
    "sh_body_is_valid(world, 42)",
]


def syntax_check(compiler, language, call, tmp_path):
    source = tmp_path / ("ids." + ("cpp" if language == "c++" else "c"))
    source.write_text(PRELUDE % call)
    standard = "-std=c++17" if language == "c++" else "-std=c99"
    return subprocess.run(
        [compiler, "-x", language, standard, "-fsyntax-only", "-I", str(INCLUDE_DIR), str(source)],
        capture_output=True,
        text=True,
    )


@pytest.mark.parametrize("call", RIGHT)
def test_the_right_id_kind_compiles(cc, call, tmp_path):
    result = syntax_check(cc, "c", call, tmp_path)
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("call", WRONG)
def test_another_id_kind_does_not_compile(cc, call, tmp_path):
    result = syntax_check(cc, "c", call, tmp_path)
    assert result.returncode != 0, "compiled: " + call
    assert "incompatible type" in result.stderr or "error" in result.stderr


@pytest.mark.parametrize("call", WRONG[:3])
def test_another_id_kind_does_not_compile_as_cpp(call, tmp_path):
    compiler = shutil.which("c++") or shutil.which("g++")
    if not compiler:
        pytest.skip("no C++ compiler")
    assert syntax_check(compiler, "c++", RIGHT[0], tmp_path).returncode == 0
    assert syntax_check(compiler, "c++", call, tmp_path).returncode != 0


def test_ctypes_refuses_another_id_kind():
    import ctypes

    import softhap
    from softhap import _lib

    world = softhap.World()
    tool = world.add_tool("sphere", radius=0.01)
    assert softhap._c_library.sh_tool_is_valid(world._handle, _lib.sh_tool_id(tool.id)) == 1
    with pytest.raises(ctypes.ArgumentError):
        softhap._c_library.sh_body_is_valid(world._handle, _lib.sh_tool_id(tool.id))
    with pytest.raises(ctypes.ArgumentError):
        softhap._c_library.sh_obstacle_is_valid(world._handle, tool.id)
