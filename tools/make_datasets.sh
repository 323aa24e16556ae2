#!/usr/bin/env bash
# Regenerates the bundled datasets: `femreg synth datasets/<name>/synth.yaml` into
# datasets/<name> for every dataset that has a synth.yaml, `femreg contact-data` for the
# contact sequences, `femreg organ-data` for organ_patch, `femreg hand-press-data` for
# hand_press and `femreg fracture-data` for beam_cut (beam_break and slab_tear when named;
# or only those named). The output is deterministic: rerunning on the same machine rewrites
# the same bytes (another CPU's BLAS kernels may move the last digits).
#   tools/make_datasets.sh                 # all
#   tools/make_datasets.sh demo beam_bend  # some
set -euo pipefail
cd "$(dirname "$0")/.."
FEMREG=${FEMREG:-build/femreg}
# One thread everywhere (OpenMP loops, OpenBLAS under CHOLMOD): summation order then does not
# depend on the machine's load, and the bytes come out the same.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
if [[ ! -x "$FEMREG" ]]; then
  echo "make_datasets: $FEMREG not found; build first (tools/build.sh) or set FEMREG" >&2
  exit 1
fi
names=("$@")
if [[ ${#names[@]} -eq 0 ]]; then
  for f in datasets/*/synth.yaml; do names+=("$(basename "$(dirname "$f")")"); done
  names+=(contact_pair tool_table organ_patch hand_press beam_cut)
fi
for name in "${names[@]}"; do
  dir=datasets/$name
  case $name in
    contact_pair|tool_table)  # contact sequences, from their own generator
      echo "== $name"
      rm -rf "$dir"
      "$FEMREG" contact-data --scenario "$name" --out "$dir"
      continue ;;
    organ_patch)  # the partial-view sequence, from its own generator
      echo "== $name"
      rm -rf "$dir"
      "$FEMREG" organ-data --out "$dir"
      continue ;;
    beam_cut|beam_break|slab_tear)  # fracture sequences, from their own generator
      echo "== $name"
      rm -rf "$dir"
      "$FEMREG" fracture-data --scenario "$name" --out "$dir"
      continue ;;
    hand_press)  # the ball pressed and handled (issue 38), from its own generator
      echo "== $name"
      rm -rf "$dir"
      "$FEMREG" hand-press-data --out "$dir"
      continue ;;
  esac
  [[ -f $dir/synth.yaml ]] || { echo "make_datasets: $dir/synth.yaml not found" >&2; exit 1; }
  # Only the generated parts are replaced; synth.yaml stays.
  rm -rf "$dir/clouds" "$dir/ground_truth" "$dir/truth" "$dir/scene.yaml" "$dir/README.md" "$dir/forces.csv"
  echo "== $name"
  "$FEMREG" synth "$dir/synth.yaml" --out "$dir" --force --no-progress
done
du -sh datasets
