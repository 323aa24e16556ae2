#!/usr/bin/env bash
# Robustness to sensor artefacts: makes two bundled sequences (datasets/beam_bend: a beam
# above a table, depth edges against it; datasets/block_press: a block on a table, concave
# corners) with `femreg synth`, clean, with each artefact of `femreg synth --artefact` at three
# strengths, and with all of them on at their realistic strengths (with and without the
# object leaving the view); registers every variant with the dataset's tracking scene
# (unchanged: nothing is tuned to the artefacts) and prints a Markdown table: sequence,
# artefact, strength, mean vertex error seen / hidden (mm), the seen error over the clean
# run's (seen / hidden), ms per frame (median). About 12 minutes on 2 cores.
#   tools/artefacts.sh [BUILD_DIR]
# The runs go to out/artefacts (ignored by git); docs/accuracy/robustness.md holds the table.
set -euo pipefail
cd "$(dirname "$0")/.."
FEMREG=$(realpath "${1:-build}")/femreg
SEQUENCES=(beam_bend block_press)
OUT=out/artefacts
rm -rf "$OUT"
mkdir -p "$OUT"
# One thread: the same numbers on every machine, and timings that do not fight other jobs.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1

# run SEQUENCE NAME [--artefact SPEC ...]: generate, register, keep the summary.
run() {
  local sequence=$1 name=$2
  shift 2
  name="$sequence/$name"
  mkdir -p "$OUT/$name"
  "$FEMREG" synth "datasets/$sequence/synth.yaml" --out "$OUT/$name/data" --no-progress "$@" \
    > "$OUT/$name/synth.txt"
  "$FEMREG" register --scene "$OUT/$name/data/scene.yaml" --frames "$OUT/$name/data/clouds" \
    --ground-truth "$OUT/$name/data/ground_truth" --out "$OUT/$name/run" --no-progress \
    --report none > "$OUT/$name/register.txt"
}

# artefact: three strengths, weak to strong (grazing_holes: a lower angle is stronger).
SWEEPS=(
  "flying_pixels 0.25 0.5 1"
  "quantisation 0.0625 0.125 0.25"
  "dark_holes 0.02 0.05 0.15"
  "specular_holes 3 5 10"
  "grazing_holes 75 65 50"
  "multipath 0.001 0.003 0.01"
  "flicker 0.0005 0.001 0.003"
  "flicker_dropout 0.02 0.1 0.3"
  "occluder 0.01 0.03 0.05"
  "leave_view 2 5 8"
)
ROWS=()
for sequence in "${SEQUENCES[@]}"; do
  run "$sequence" clean
  ROWS+=("$sequence clean - clean")
  for sweep in "${SWEEPS[@]}"; do
    read -r artefact strengths <<< "$sweep"
    for strength in $strengths; do
      run "$sequence" "${artefact}_$strength" --artefact "$artefact=$strength"
      ROWS+=("$sequence $artefact $strength ${artefact}_$strength")
    done
  done
  # Every artefact at its realistic strength; then without the object leaving the view, without
  # the flying pixels, and without both the flying pixels and the flicker.
  run "$sequence" all --artefact all
  ROWS+=("$sequence all realistic all")
  run "$sequence" all_but_leave_view --artefact all --artefact leave_view=0
  ROWS+=("$sequence all_but_leave_view realistic all_but_leave_view")
  run "$sequence" all_but_flying --artefact all --artefact flying_pixels=0
  ROWS+=("$sequence all_but_flying_pixels realistic all_but_flying")
  run "$sequence" all_but_flying_flicker --artefact all --artefact flying_pixels=0 \
    --artefact flicker=0
  ROWS+=("$sequence all_but_flying_pixels_flicker realistic all_but_flying_flicker")
done
printf '%s\n' "${ROWS[@]}" > "$OUT/rows.txt"
/usr/bin/python3 - "$OUT" <<'PY'
import json
import sys

out = sys.argv[1]
rows = [line.split() for line in open(f"{out}/rows.txt") if line.strip()]


def summary(name):
    with open(f"{out}/{name}/run/summary.json") as f:
        return json.load(f)


print("| sequence | artefact | strength | mean error seen / hidden (mm) "
      "| over clean: seen / hidden | ms/frame |")
print("|---|---|---:|---|---|---:|")
for sequence, artefact, strength, name in rows:
    s = summary(f"{sequence}/{name}")
    e = s["vertex_error_mm"]
    c = summary(f"{sequence}/clean")["vertex_error_mm"]
    print(f"| {sequence} | {artefact} | {strength} | {e['seen_mean']:.2f} / {e['hidden_mean']:.2f} "
          f"| {e['seen_mean'] / c['seen_mean']:.2f} / {e['hidden_mean'] / c['hidden_mean']:.2f} "
          f"| {s['ms_per_frame_median']:.0f} |")
PY
