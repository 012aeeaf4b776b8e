"""The tree's layers (scripts/check_layers.py): the real tree passes, and each kind of violation
the check exists for is caught in a small tree made here."""

import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHECK = os.path.join(ROOT, "scripts", "check_layers.py")


def run_check(root):
    return subprocess.run([sys.executable, CHECK, root], capture_output=True, text=True)


def make_tree(tmp_path, files):
    for rel, text in files.items():
        path = tmp_path / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return str(tmp_path)


def test_the_library_tree_has_no_upward_include():
    result = run_check(ROOT)
    assert result.returncode == 0, result.stdout


CLEAN = {
    "src/core/memory.hpp": "#pragma once\n",
    "src/model/body.hpp": '#include "core/memory.hpp"\n#include "linalg/sparse_system.hpp"\n',
    "src/linalg/sparse_system.hpp": '#include "core/memory.hpp"\n',
    "src/world/world.cpp": '#include "world/world.hpp"\n#include "model/body.hpp"\n',
    "src/mesh/io/writer.cpp": "#include <fstream>\n",
    "tests/internal/test_x.cpp": '#include "model/body.hpp"\n',
    "examples/minimal.c": "#include <softhap/softhap.h>\n",
}


def test_a_tree_that_follows_the_layers_passes(tmp_path):
    result = run_check(make_tree(tmp_path, CLEAN))
    assert result.returncode == 0, result.stdout


@pytest.mark.parametrize(
    "rel, text, message",
    [
        ("src/world/world.cpp", '#include "haptic/haptic_context.hpp"\n', 'world includes "haptic/haptic_context.hpp"'),
        ("src/model/fem.cpp", '#include "solver/sparse_system.hpp"\n', "solver is on a higher layer"),
        ("src/mesh/tet_mesh.cpp", '#include "material/law.hpp"\n', "material is on its own row"),
        ("src/model/body.cpp", "#include <fstream>\n", "file I/O outside src/mesh/io"),
        ("src/model/body.cpp", '  FILE* f = fopen(path, "w");\n', "file I/O outside src/mesh/io"),
        ("src/gadgets/thing.cpp", "\n", "folder src/gadgets is not in the layer table"),
        ("bench/bench.c", '#include "world/world.hpp"\n', 'includes library internals "world/world.hpp"'),
    ],
)
def test_each_kind_of_violation_is_reported_with_file_and_line(tmp_path, rel, text, message):
    files = dict(CLEAN)
    files[rel] = files.get(rel, "") + text
    result = run_check(make_tree(tmp_path, files))
    assert result.returncode == 1
    line = len(files[rel].splitlines())
    assert "%s:%d: " % (rel, line) in result.stdout and message in result.stdout, result.stdout
