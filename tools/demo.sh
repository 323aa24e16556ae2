#!/usr/bin/env bash
# The main job: install what is missing, build, register the bundled demo sequence against
# its ground truth, print the summary and write the results to out/demo (open
# out/demo/beam.pvd in ParaView; per-frame numbers in out/demo/stats.csv).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
OUT=${OUT:-out/demo}
build/femreg register \
  --scene datasets/demo/scene.yaml \
  --frames datasets/demo/clouds \
  --ground-truth datasets/demo/ground_truth \
  --out "$OUT" --force "$@"
