#!/bin/sh
# Remakes tests/fixtures/calculix_sag/ (the calibration test case) with CalculiX:
# the scene's mesh as C3D4 at the true E (2e5 Pa) solved by ccx with NLGEOM, then the
# deformed surface sampled without noise (surface.pcd) and rendered by the scene's camera
# with the virtual sensor's noise (camera.pcd), and ccx's displacements (calculix_u.csv).
#   tools/make_calculix_sag.sh [BUILD_DIR]
# BUILD_DIR (default: build) must hold femreg_calculix_case; needs ccx (Debian:
# calculix-ccx, in tools/setup.sh's optional packages). Not run by CI: the outputs are
# checked in and tests/calibration_test.cc reads them.
set -e
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "${1:-$here/../build}" && pwd)
tool="$build/femreg_calculix_case"
[ -x "$tool" ] || { echo "make_calculix_sag.sh: $tool not found; build femreg_calculix_case" >&2; exit 1; }
command -v ccx >/dev/null || { echo "make_calculix_sag.sh: ccx (calculix-ccx) not found" >&2; exit 1; }
case_dir="$here/../tests/fixtures/calculix_sag"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$tool" deck "$case_dir/scene.yaml" "$work/sag.inp" E=2e5
(cd "$work" && ccx sag > ccx.log 2>&1) || { tail -20 "$work/ccx.log" >&2; exit 1; }
grep -q "Job finished" "$work/ccx.log" || { tail -20 "$work/ccx.log" >&2; exit 1; }
"$tool" clouds "$case_dir/scene.yaml" "$work/sag.dat" "$work" seed=1 samples=4000
for f in calculix_u.csv surface.pcd camera.pcd; do cp "$work/$f" "$case_dir/$f"; done
ccx_version=$(ccx -v 2>/dev/null | grep -o 'Version [0-9.]*' | head -1)
echo "made with CalculiX $ccx_version: $case_dir"
