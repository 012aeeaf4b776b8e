"""Loading the C library: lookup order, version check, status names, Error, freeing handles."""

import os
import pickle
import shutil

import pytest

import softhap
from conftest import compile_c, run_python
from softhap import _lib


def test_version_is_0_6_0():
    # SH_VERSION of include/softhap/softhap.h: 0 * 1000000 + 6 * 1000 + 0.
    assert softhap.SH_VERSION == 6000
    assert softhap.version() == 6000
    assert softhap.__version__ == "0.6.0"
    assert softhap.version_string(2003004) == "2.3.4"


def test_build_features_match_the_cmake_options():
    features = softhap.build_features()
    assert features <= {"SH_FEATURE_CHOLMOD", "SH_FEATURE_CCD"}
    # If the library sits in a CMake build tree, its cache says which options were ON.
    cache = os.path.join(os.path.dirname(os.path.realpath(softhap.library_path)), "CMakeCache.txt")
    if not os.path.isfile(cache):
        pytest.skip("the library is not in a CMake build tree")
    options = {}
    with open(cache) as text:
        for line in text:
            if line.startswith("SOFTHAP_WITH_") and ":BOOL=" in line:
                name, value = line.strip().split(":BOOL=")
                options[name] = value.upper() in ("ON", "1", "TRUE", "YES")
    assert ("SH_FEATURE_CHOLMOD" in features) == options["SOFTHAP_WITH_CHOLMOD"]
    assert ("SH_FEATURE_CCD" in features) == options["SOFTHAP_WITH_CCD"]


def test_library_path_comes_from_environment_when_set():
    if os.environ.get("SOFTHAP_LIBRARY"):
        assert softhap.library_path == os.environ["SOFTHAP_LIBRARY"]
    assert os.path.isfile(softhap.library_path)


def test_lookup_order(tmp_path):
    package_dir = tmp_path / "pkg"
    repo_dir = tmp_path / "repo"
    (repo_dir / "build").mkdir(parents=True)
    package_dir.mkdir()
    beside = package_dir / "libsofthap.so"
    in_build = repo_dir / "build" / "libsofthap.so"
    explicit = tmp_path / "custom" / "libother.so"
    explicit.parent.mkdir()

    def find(environ):
        return _lib.find_library(environ, str(package_dir), str(repo_dir))

    # nothing anywhere: ImportError naming every place looked at and the variable
    with pytest.raises(ImportError) as info:
        find({})
    assert str(beside) in str(info.value) and str(in_build) in str(info.value)
    assert "SOFTHAP_LIBRARY" in str(info.value)

    in_build.write_bytes(b"")
    assert find({}) == str(in_build)
    beside.write_bytes(b"")
    assert find({}) == str(beside)  # next to the package wins over the build tree
    explicit.write_bytes(b"")
    assert find({"SOFTHAP_LIBRARY": str(explicit)}) == str(explicit)  # the variable wins

    # a set variable naming a missing file is an error, not a silent fallback
    with pytest.raises(ImportError) as info:
        find({"SOFTHAP_LIBRARY": str(tmp_path / "missing.so")})
    assert "missing.so" in str(info.value)


def test_import_uses_softhap_library_variable(tmp_path):
    copy = tmp_path / "renamed_softhap.so"
    shutil.copyfile(softhap.library_path, copy)
    result = run_python(
        "import softhap; print(softhap.library_path); print(softhap.version())",
        {"SOFTHAP_LIBRARY": str(copy)},
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == [str(copy), "6000"]


def test_import_fails_clearly_when_variable_names_missing_file(tmp_path):
    missing = tmp_path / "nowhere" / "libsofthap.so"
    result = run_python("import softhap", {"SOFTHAP_LIBRARY": str(missing)})
    assert result.returncode != 0
    assert "ImportError" in result.stderr
    assert str(missing) in result.stderr and "SOFTHAP_LIBRARY" in result.stderr


def test_version_mismatch_is_refused_monkeypatched(monkeypatch):
    monkeypatch.setattr(_lib, "SH_VERSION", 2000000)
    with pytest.raises(ImportError) as info:
        _lib.load_library(softhap.library_path)
    text = str(info.value)
    assert "version mismatch" in text
    assert "0.6.0" in text and "2.0.0" in text


def test_version_mismatch_is_refused_on_import(cc, tmp_path):
    # A library that claims version 2.0.0: importing the package must refuse it.
    fake = compile_c(
        cc,
        "#include <stdint.h>\n"
        "__attribute__((visibility(\"default\"))) int32_t sh_version(void) { return 2000000; }\n",
        tmp_path / "libfake.so",
        shared=True,
    )
    result = run_python("import softhap", {"SOFTHAP_LIBRARY": str(fake)})
    assert result.returncode != 0
    assert "ImportError" in result.stderr
    assert "version mismatch" in result.stderr
    assert "2.0.0" in result.stderr and "0.6.0" in result.stderr


def test_not_a_softhap_library_is_refused(cc, tmp_path):
    other = compile_c(cc, "int something_else(void) { return 1; }\n", tmp_path / "libx.so", shared=True)
    with pytest.raises(ImportError) as info:
        _lib.load_library(str(other))
    assert "sh_version" in str(info.value)


def test_status_names_and_strings():
    assert softhap.Status.SH_ERR_PARSE == 6
    assert softhap.status_name(6) == "SH_ERR_PARSE"
    assert softhap.status_name(99) == "SH_STATUS_99"
    for status in softhap.Status:
        assert softhap.status_string(status).startswith(status.name)
    assert [w.name for w in softhap.WarningKind] == [
        "SH_WARN_UNSTABLE",
        "SH_WARN_SUBSTEPPED",
        "SH_WARN_INVERTED",
        "SH_WARN_CAPACITY",
        "SH_WARN_FORCE_CLAMPED",
        "SH_WARN_LOCKING",
        "SH_WARN_NOT_CONVERGED",
    ]


def test_error_carries_status_name_and_message(meshes):
    with pytest.raises(softhap.Error) as info:
        softhap.Mesh.load(meshes / "does_not_exist.msh")
    error = info.value
    assert error.status == softhap.Status.SH_ERR_IO
    assert isinstance(error.status, int) and error.status == 5
    assert error.status_name == "SH_ERR_IO"
    assert error.function == "sh_mesh_load"
    assert error.message  # the C library's detail
    assert "SH_ERR_IO" in str(error) and error.message in str(error)
    assert error.report is None
    copy = pickle.loads(pickle.dumps(error))  # e.g. across multiprocessing
    assert (copy.status, copy.message, copy.function) == (error.status, error.message, error.function)


_HANDLE_FREEING = r"""
import gc, sys
import softhap
from softhap._loaded import lib
BUSY = int(softhap.Status.SH_ERR_BUSY)

def busy():
    # sh_set_allocator(NULL) is refused with SH_ERR_BUSY while any softhap object is alive.
    return lib.sh_set_allocator(None) == BUSY

mesh = softhap.Mesh.load(MESH)
assert busy()
mesh.close()
mesh.close()  # twice is fine
assert not busy(), "close() did not free the mesh"

mesh = softhap.Mesh.load(MESH)
del mesh
gc.collect()
assert not busy(), "garbage collection did not free the mesh"

with softhap.Mesh.load(MESH) as mesh:
    assert busy()
assert not busy(), "leaving a with block did not free the mesh"

with softhap.World() as world:
    assert busy()
assert not busy(), "leaving a with block did not free the world"

mesh = softhap.Mesh.load(MESH)
world = softhap.World()
body = world.add_fem_body(mesh)
mesh.close()
del world
gc.collect()
assert busy(), "the body should keep its world alive"
assert body.node_count == 181
del body
gc.collect()
assert not busy(), "the world was not freed with its last body"
print("ok")
"""


def test_handles_are_freed_deterministically(meshes):
    code = "MESH = %r\n" % str((meshes / "liver.msh").resolve()) + _HANDLE_FREEING
    result = run_python(code)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"
