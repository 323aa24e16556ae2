#!/usr/bin/env bash
# Installs every Debian package that femreg's build, tests, demo and documentation
# (tools/docs.sh) need (nothing when all are present), then builds the femreg Python package
# for Debian's python3 and installs it into its site directory
# (/usr/local/lib/python3.11/dist-packages), so that
# `python3 -c "import femreg"` works. On Debian 12; root (or sudo) is needed only to install
# (with every package present and without root, it skips the Python package's install).
# FEMREG_SETUP_PYTHON=0 skips the Python package; FEMREG_WITH_OPEN3D=1 adds python3-open3d
# (optional); BUILD_DIR (default build) and JOBS as in tools/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev
  libceres-dev libgoogle-glog-dev libgflags-dev
  libsuitesparse-dev libopenblas-dev liblapack-dev
  libpcl-dev libvtk9-dev
  libnanoflann-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev libyaml-cpp-dev nlohmann-json3-dev
  libtet1.5-dev
  libcgal-dev libgmp-dev libmpfr-dev
  libpng-dev zlib1g-dev
  python3 python3-dev python3-matplotlib python3-numpy python3-pytest pybind11-dev python3-venv
  python3-sphinx python3-myst-parser python3-sphinx-rtd-theme
)
# Only for the cross-check against an independent FEM code (tools/compare_calculix.sh).
OPTIONAL=(calculix-ccx)

want=("${PACKAGES[@]}")
if [ "${FEMREG_WITH_CALCULIX:-1}" = 1 ]; then want+=("${OPTIONAL[@]}"); fi
# Open3D, only on request (FEMREG_WITH_OPEN3D=1): femreg does not need it; with it, the Python
# package takes Open3D's clouds and images, examples/open3d_view.py runs, and
# python/tests/test_open3d.py stops skipping.
if [ "${FEMREG_WITH_OPEN3D:-0}" = 1 ]; then want+=(python3-open3d); fi

missing=()
for p in "${want[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# Root (or sudo) only for what needs it: installing packages and the Python package.
SUDO=""
have_root() {
  if [ "$(id -u)" = 0 ]; then return 0; fi
  command -v sudo >/dev/null || return 1
  sudo -n true 2>/dev/null || return 1  # sudo that would ask for a password is no sudo here
  SUDO=sudo
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#want[@]} packages present"
else
  have_root || { echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  echo "setup: installing ${#missing[@]} package(s): ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  echo "setup: packages done"
fi

# The Python package, for Debian's interpreter (the one with python3-numpy), in the same
# build folder as tools/build.sh (an up-to-date build costs nothing).
if [ "${FEMREG_SETUP_PYTHON:-1}" = 1 ] && ! have_root; then
  echo "setup: no root or sudo: the Python package is not installed for python3 (the tests use the build's own)"
elif [ "${FEMREG_SETUP_PYTHON:-1}" = 1 ]; then
  BUILD_DIR=${BUILD_DIR:-build}
  JOBS=${JOBS:-$(nproc)}
  echo "setup: building the femreg Python package in $BUILD_DIR"
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DFEMREG_BUILD_PYTHON=ON \
    -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
  cmake --build "$BUILD_DIR" --target femreg_python -j "$JOBS" >/dev/null
  $SUDO cmake --install "$BUILD_DIR" --component python >/dev/null
  (cd / && /usr/bin/python3 -c "import femreg; print('setup: python3 -c \"import femreg\" works (' + femreg.__file__ + ')')")
fi
echo "setup: done"
