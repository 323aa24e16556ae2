#!/bin/sh
# Compares femreg's forward solve with CalculiX on the same C3D4 meshes and loads:
# femreg linear vs ccx linear (should agree to ~1e-6), femreg corotational vs ccx NLGEOM, and
# contact: a block pressed onto a block or a rigid plane, with and without friction (*CONTACT PAIR),
# and separation: a bent beam cut by removing a slab of its elements (*MODEL CHANGE).
#   tools/compare_calculix.sh [BUILD_DIR] [--keep DIR] [--only single|contact|cut] [--markdown FILE]
#                             [--fixture DIR]
# BUILD_DIR (default: build) must hold femreg_forward_probe (FEMREG_BUILD_TOOLS=ON):
#   cmake -S . -B build && make -C build -j2 femreg_forward_probe
set -e
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../build}
[ $# -gt 0 ] && shift
probe="$(cd "$build" && pwd)/femreg_forward_probe"
if [ ! -x "$probe" ]; then
  echo "compare_calculix.sh: $probe not found; build the femreg_forward_probe target" >&2
  exit 1
fi
command -v ccx >/dev/null || { echo "compare_calculix.sh: ccx (calculix-ccx) not found" >&2; exit 1; }
exec /usr/bin/python3 "$here/compare_calculix.py" "$probe" "$@"
