"""pytest setup for the softhap Python bindings: puts bindings/python on sys.path (so that
`import softhap` works without installing) and provides shared fixtures."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO_DIR = Path(__file__).resolve().parents[2]
BINDINGS_DIR = REPO_DIR / "bindings" / "python"
INCLUDE_DIR = REPO_DIR / "include"

if str(BINDINGS_DIR) not in sys.path:
    sys.path.insert(0, str(BINDINGS_DIR))


def _meshes_dir():
    """The shared test meshes: $SOFTHAP_SHARED_DIR/meshes, ../shared/meshes from the working
    directory (the repo root), or shared/meshes beside the checkout."""
    candidates = []
    if os.environ.get("SOFTHAP_SHARED_DIR"):
        candidates.append(Path(os.environ["SOFTHAP_SHARED_DIR"]) / "meshes")
    candidates.append(Path("../shared/meshes"))
    candidates.append(REPO_DIR.parent / "shared" / "meshes")
    for candidate in candidates:
        if (candidate / "liver.msh").is_file():
            return candidate
    return candidates[-1]


MESHES_DIR = _meshes_dir()


@pytest.fixture(scope="session")
def meshes():
    """Directory holding the shared test meshes (see shared/meshes/README.md)."""
    if not (MESHES_DIR / "liver.msh").is_file():
        pytest.fail("shared test meshes not found (looked in %s)" % MESHES_DIR)
    return MESHES_DIR


@pytest.fixture(scope="session")
def cc():
    """Path of a C compiler, or skip the test."""
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not compiler:
        pytest.skip("no C compiler (cc) available")
    return compiler


def compile_c(cc_path, source_text, output, shared=False, workdir=None):
    """Compile C source text into output (an executable, or a shared library if shared)."""
    workdir = Path(workdir or Path(output).parent)
    source = workdir / (Path(output).name + ".c")
    source.write_text(source_text)
    command = [cc_path, "-std=c99", "-I", str(INCLUDE_DIR), str(source), "-o", str(output)]
    if shared:
        command[1:1] = ["-shared", "-fPIC"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        pytest.fail("compiling %s failed:\n%s" % (source, result.stderr))
    return Path(output)


def run_python(code, env_updates=None, remove_env=()):
    """Run code in a fresh Python interpreter with bindings/python on its path; return the
    CompletedProcess (stdout, stderr, returncode)."""
    env = dict(os.environ)
    for name in remove_env:
        env.pop(name, None)
    env.update(env_updates or {})
    env["PYTHONPATH"] = str(BINDINGS_DIR) + os.pathsep + env.get("PYTHONPATH", "")
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=str(REPO_DIR)
    )


def pytest_configure(config):
    """The tests load the shared meshes in their files' units and scale them themselves, which
    the size check (softhap.UnitsWarning) rightly questions; test_mesh_exchange checks that
    warning with pytest.warns, which sees it whatever the filters say."""
    config.addinivalue_line("filterwarnings", "ignore:.*m across")
