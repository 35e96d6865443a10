#!/usr/bin/env bash
# Installs the Debian packages corrlap needs, only those missing. Needs root (or sudo).
# --vtk also installs VTK's Python module (large), which the MetaImage cross-checks with VTK use;
# without it those checks skip with a message. CI asks for it.
# --bench also installs what bench/compare_surfaces.py runs against (VTK, scikit-image, Open3D)
# and GNU time (its peak-memory figures);
# `make test` does not need them (their test skips with a message).
# --petsc also installs PETSc, SLEPc and Open MPI (the petsc/slepc backends, -DCORRLAP_WITH_PETSC=ON;
# docs/backends.md).
# --chromium also installs Chromium, which the browser test of the HTML viewer (ctest viewer_browser)
# drives; without it that test skips with a message. CI asks for it.
# node and npm (Debian's nodejs, npm) are installed unless an npm is already on the PATH: the build
# bundles the HTML viewer's script with them (viewer/README.md).
set -euo pipefail
packages=(cmake ninja-build g++ ccache pkg-config python3
          libeigen3-dev libsuitesparse-dev libopenblas-dev libspectra-dev libtbb-dev
          doctest-dev nlohmann-json3-dev libcli11-dev libbenchmark-dev zlib1g-dev libpng-dev libtiff-dev clang-format
          clang-14 libclang-rt-14-dev python3-numpy python3-matplotlib python3-pytest
          python3-dev python3-scipy pybind11-dev
          python3-nibabel python3-tifffile)
for arg in "$@"; do
  case "$arg" in
    --vtk) packages+=(python3-vtk9) ;;
    --bench) packages+=(python3-vtk9 python3-skimage python3-open3d time) ;;
    --petsc) packages+=(libpetsc-real-dev libslepc-real-dev openmpi-bin libopenmpi-dev) ;;
    --chromium) packages+=(chromium) ;;
    *) echo "install_deps.sh: unknown option '$arg' (known: --vtk, --bench, --petsc, --chromium)" >&2; exit 2 ;;
  esac
done
if ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "corrlap: installing missing Debian packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "corrlap: error: need root to install: ${missing[*]}" >&2; exit 1; fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
