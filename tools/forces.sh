#!/usr/bin/env bash
# Registers every bundled sequence with ground truth with the classic energy and with the
# forces estimated (the physical mode, registration.forces.estimate), one thread each, and
# writes two tables: the vertex errors (seen / hidden), resultant-force errors and time per
# frame of the sequences that carry the true external force (forces.csv: organ_patch,
# hand_press, tool_table; those also pushing only, with the friction they were made with;
# every sequence with forces.csv also with forces.adaptive_weight) to
# docs/accuracy/forces.md, and the vertex errors, time and frames
# converged of both modes on every sequence to docs/accuracy/physical_mode.md.
# About two minutes on one core (16 sequences, 2026-12-02); run it on a quiet machine for the times.
#   tools/forces.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
FEMREG=${1:-build}/femreg
OUT=out/forces  # the runs (ignored by git); the table goes to docs/accuracy/forces.md
rm -rf "$OUT"
mkdir -p "$OUT"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1} OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
names=()
for dir in datasets/*/; do
  name=$(basename "$dir")
  [[ -f "$dir/scene.yaml" && -d "$dir/clouds" && -d "$dir/ground_truth" ]] && names+=("$name")
done
# The contacts' friction the sequences with a true force were made with: organ_patch's tool is
# frictionless (its README), tool_table's tool and table press by a contact penalty without
# friction (femreg contact-data); hand_press's hand sticks (its README; -1: no bound).
declare -A FRICTION=([organ_patch]=0 [tool_table]=0 [hand_press]=-1)
for name in "${names[@]}"; do
  echo "forces.sh: $name" >&2
  modes=(classic physical)
  [[ -n "${FRICTION[$name]:-}" ]] && modes+=(pushing)
  [[ -f "datasets/$name/forces.csv" ]] && modes+=(adaptive)
  for mode in "${modes[@]}"; do
    # classic: in every frame, also where a hand holds the body (forces.when_occluded)
    flag=(--set registration.forces.when_occluded=false)
    [[ $mode != classic ]] && flag=(--set registration.forces.estimate=true)
    [[ $mode == adaptive ]] && flag+=(--set registration.forces.adaptive_weight=true)
    [[ $mode == pushing ]] && flag+=(--set registration.forces.pushing_only=true
                                     --set "registration.forces.friction=${FRICTION[$name]}")
    run="$OUT/${name}_$mode"
    "$FEMREG" register --scene "datasets/$name/scene.yaml" --frames "datasets/$name/clouds" \
      --ground-truth "datasets/$name/ground_truth" --out "$run" --threads 1 \
      --no-progress --report none "${flag[@]}" > "$run.txt"
    "$FEMREG" eval "$run" "datasets/$name" > "$run.eval.txt"
  done
done
"${FEMREG_PYTHON:-python3}" tools/forces_table.py "$OUT" > docs/accuracy/forces.md
"${FEMREG_PYTHON:-python3}" tools/forces_table.py "$OUT" --modes > docs/accuracy/physical_mode.md
cat docs/accuracy/forces.md docs/accuracy/physical_mode.md
