#!/usr/bin/env bash
# Registers the bundled contact sequences (contact_pair, tool_table) with collision on and off
# (`femreg register --no-collision`, which still measures the penetration), on the Ceres and
# the fast back end, and writes the per-frame table of vertex errors (seen / hidden) and
# deepest penetration to docs/accuracy/contacts.md. About a minute on 2 cores.
#   tools/contacts.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
FEMREG=${1:-build}/femreg
OUT=out/contacts  # the runs (ignored by git); the table goes to docs/accuracy/contacts.md
rm -rf "$OUT"
mkdir -p "$OUT"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1} OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
for name in contact_pair tool_table; do
  for backend in ceres fast; do
    scene="$OUT/${name}_${backend}.yaml"
    # The dataset's scene with the back end set; paths in it stay relative to the dataset.
    sed "s/solver: {/solver: {backend: $backend, /" "datasets/$name/scene.yaml" > "$scene"
    sed -i "s|mesh: tool.stl|mesh: ../../datasets/$name/tool.stl|" "$scene"
    for mode in on off; do
      flag=""
      [[ $mode == off ]] && flag=--no-collision
      "$FEMREG" register --scene "$scene" --frames "datasets/$name/clouds" \
        --ground-truth "datasets/$name/ground_truth" --out "$OUT/${name}_${backend}_$mode" \
        --no-progress --report none $flag > "$OUT/${name}_${backend}_$mode.txt"
    done
  done
done
"${FEMREG_PYTHON:-python3}" tools/contact_tables.py "$OUT" > docs/accuracy/contacts.md
cat docs/accuracy/contacts.md
