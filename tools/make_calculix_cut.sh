#!/bin/sh
# Remakes datasets/beam_cut_calculix/: beam_cut's sequence (a soft beam bent, then cut) with its
# ground truth solved by CalculiX instead of femreg: the deck of
# `femreg fracture-data --scenario beam_cut --calculix-deck` (the 40 x 6 x 6 mesh as C3D4,
# *ELASTIC under NLGEOM, one step per frame, the slab removed by *MODEL CHANGE in the cut
# frame's step) solved by ccx, then the sequence written from ccx's displacements
# (`--calculix-result`): the same clouds' camera, scene and ground-truth files as beam_cut.
#   tools/make_calculix_cut.sh [BUILD_DIR] [OUT_DIR]
# BUILD_DIR (default: build) must hold femreg; needs ccx (Debian: calculix-ccx, in
# tools/setup.sh's optional packages). Not run by CI: the dataset is checked in.
set -e
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "${1:-$here/../build}" && pwd)
out=${2:-$here/../datasets/beam_cut_calculix}
femreg="$build/femreg"
[ -x "$femreg" ] || { echo "make_calculix_cut.sh: $femreg not found; build femreg" >&2; exit 1; }
command -v ccx >/dev/null || { echo "make_calculix_cut.sh: ccx (calculix-ccx) not found" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$femreg" fracture-data --scenario beam_cut --calculix-deck "$work/cut.inp"
(cd "$work" && OMP_NUM_THREADS=1 ccx cut > ccx.log 2>&1) || { tail -20 "$work/ccx.log" >&2; exit 1; }
grep -q "Job finished" "$work/ccx.log" || { tail -20 "$work/ccx.log" >&2; exit 1; }
"$femreg" fracture-data --scenario beam_cut --calculix-result "$work/cut.dat" --out "$out" --force
ccx_version=$(ccx -v 2>/dev/null | grep -o 'Version [0-9.]*' | head -1)
echo "made with CalculiX $ccx_version: $out"
