#!/usr/bin/env bash
# Regenerates the data of "What accuracy costs in time" (docs/performance/accuracy.md, which
# includes them): femreg bench and femreg compare on the bundled datasets, their CSVs and
# plots in docs/accuracy/, and the markdown tables (docs/accuracy/tables.md). About a minute
# on 2 cores (2026-11-27); run on a quiet machine.
#   tools/accuracy.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
FEMREG=${1:-build}/femreg
OUT=docs/accuracy
mkdir -p "$OUT"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
"$FEMREG" bench --force --out "$OUT/bench" \
  --dataset datasets/demo --dataset datasets/beam_bend --dataset datasets/block_press
"$FEMREG" compare --force --out "$OUT/compare" \
  --dataset datasets/demo --dataset datasets/beam_bend --dataset datasets/block_press \
  --dataset datasets/slab_stretch --dataset datasets/fast_motion --dataset datasets/occlusion
"${FEMREG_PYTHON:-python3}" tools/accuracy_tables.py "$OUT"/bench/*_bench.csv "$OUT"/compare/*_compare.csv \
  > "$OUT/tables.md"
echo "Tables: $OUT/tables.md; plots: $OUT/bench/bench.png, $OUT/compare/compare.png"
