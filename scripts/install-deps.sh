#!/usr/bin/env bash
# Installs what softhap needs and is missing: Debian packages and Python packages.
# Safe to run repeatedly; does nothing when everything is present.
# `install-deps.sh fuzz` also installs clang and its libFuzzer/sanitizer runtimes (make fuzz only:
# make test builds with the system's GCC and does not need them). `install-deps.sh optional`
# also installs the optional Python packages whose tests are otherwise skipped (CI runs it):
# pyvista (softhap.viz; brings VTK, ~150 MB) and pytetwild (softhap.tetrahedralize).
set -euo pipefail

# libopenblas0-serial: an optimised single-threaded BLAS for CHOLMOD's supernodal factorisation
# and solves (Debian's default reference BLAS makes them ~2.5x and ~1.9x slower). Installing it
# makes it the system's libblas.so.3 through update-alternatives.
debian_packages=(libeigen3-dev libccd-dev libsuitesparse-dev libopenblas0-serial libcmocka-dev pkg-config)
# libclang-rt-14-dev holds libFuzzer (libclang_rt.fuzzer*.a) and clang's ASan/UBSan runtimes.
if [ "${1:-}" = fuzz ]; then
  debian_packages+=(clang libclang-rt-14-dev)
fi
missing=()
for package in "${debian_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing Debian packages: ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${missing[@]}" </dev/null
fi

# meshio (pure Python, MIT) lets the tests read and write binary meshes through Mesh.load and
# Mesh.to_meshio; the library itself runs without it.
python=${PYTHON:-python3}
# make pip-check makes a venv: Debian's python3 needs python3-venv for it (ensurepip).
if ! "$python" -c "import ensurepip, venv" 2>/dev/null; then
  echo "install-deps: installing python3-venv"
  sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq python3-venv </dev/null
fi
if ! "$python" -c "import numpy, pytest, meshio" 2>/dev/null; then
  echo "install-deps: installing numpy, pytest and meshio with pip"
  "$python" -m pip install -q numpy pytest meshio </dev/null ||
    "$python" -m pip install -q --break-system-packages numpy pytest meshio </dev/null
fi

if [ "${1:-}" = optional ] && ! "$python" -c "import pyvista, pytetwild" 2>/dev/null; then
  echo "install-deps: installing pyvista and pytetwild with pip"
  "$python" -m pip install -q pyvista pytetwild </dev/null ||
    "$python" -m pip install -q --break-system-packages pyvista pytetwild </dev/null
fi
