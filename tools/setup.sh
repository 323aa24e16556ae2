#!/usr/bin/env bash
# Installs every Debian package that femreg's build, tests and demo need.
# Does nothing when all are present. Run as root (or with sudo) on Debian 12.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git
  libeigen3-dev
  libceres-dev libgoogle-glog-dev libgflags-dev
  libsuitesparse-dev libopenblas-dev liblapack-dev
  libpcl-dev libvtk9-dev
  libnanoflann-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev libyaml-cpp-dev nlohmann-json3-dev
  libtet1.5-dev
  python3 python3-matplotlib python3-numpy
)
# Only for the cross-check against an independent FEM code (tools/compare_calculix.sh).
OPTIONAL=(calculix-ccx)

want=("${PACKAGES[@]}")
if [ "${FEMREG_WITH_CALCULIX:-1}" = 1 ]; then want+=("${OPTIONAL[@]}"); fi

missing=()
for p in "${want[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#want[@]} packages present"
  exit 0
fi

echo "setup: installing ${#missing[@]} package(s): ${missing[*]}"
SUDO=""
if [ "$(id -u)" != 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root or sudo to install packages" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
