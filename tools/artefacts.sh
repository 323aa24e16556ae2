#!/usr/bin/env bash
# Robustness to sensor artefacts: makes the beam_bend sequence (datasets/beam_bend/synth.yaml)
# with `femreg synth`, clean and with each artefact of `femreg synth --artefact` at three
# strengths and with all of them on at their realistic strengths, registers every variant
# with the dataset's tracking scene (unchanged: nothing is tuned to the artefacts) and prints
# a Markdown table: artefact, strength, mean vertex error seen / hidden (mm) and the ratio of
# the seen error to the clean run's, ms per frame (median). About 5 minutes on 2 cores.
#   tools/artefacts.sh [BUILD_DIR]
# The runs go to out/artefacts (ignored by git); docs/accuracy/robustness.md holds the table.
set -euo pipefail
cd "$(dirname "$0")/.."
FEMREG=$(realpath "${1:-build}")/femreg
SCENE=datasets/beam_bend/synth.yaml
OUT=out/artefacts
rm -rf "$OUT"
mkdir -p "$OUT"
# One thread: the same numbers on every machine, and timings that do not fight other jobs.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1

# run NAME [--artefact SPEC ...]: generate, register, keep the summary.
run() {
  local name=$1
  shift
  "$FEMREG" synth "$SCENE" --out "$OUT/$name/data" --no-progress "$@" > "$OUT/$name/synth.txt"
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
ROWS=("clean - clean")
mkdir -p "$OUT/clean"
run clean
for sweep in "${SWEEPS[@]}"; do
  read -r artefact strengths <<< "$sweep"
  for strength in $strengths; do
    name="${artefact}_${strength}"
    mkdir -p "$OUT/$name"
    run "$name" --artefact "$artefact=$strength"
    ROWS+=("$artefact $strength $name")
  done
done
# Every artefact at its realistic strength, and every one but the object leaving the view.
mkdir -p "$OUT/all" "$OUT/all_but_leave_view"
run all --artefact all
ROWS+=("all realistic all")
run all_but_leave_view --artefact all --artefact leave_view=0
ROWS+=("all_but_leave_view realistic all_but_leave_view")

printf '%s\n' "${ROWS[@]}" | /usr/bin/python3 -c '
import json, sys
out = sys.argv[1]
rows = [line.split() for line in sys.stdin if line.strip()]
def summary(name):
    with open(f"{out}/{name}/run/summary.json") as f:
        return json.load(f)
clean = summary("clean")["vertex_error_mm"]["seen_mean"]
print("| artefact | strength | seen / hidden mean error (mm) | seen / clean | ms/frame |")
print("|---|---:|---|---:|---:|")
for artefact, strength, name in rows:
    s = summary(name)
    e = s["vertex_error_mm"]
    print(f"| {artefact} | {strength} | {e[\"seen_mean\"]:.2f} / {e[\"hidden_mean\"]:.2f} "
          f"| {e[\"seen_mean\"] / clean:.2f} | {s[\"ms_per_frame_median\"]:.0f} |")
' "$OUT"
