#!/usr/bin/env bash
# The global initial pose on the public bunny (registration.initial_pose): the bunny scene of
# tools/public_meshes/ without its anchors, a femreg synth sequence, then femreg register with
# the rest mesh turned by 0.5, 1.2 and 2.5 rad about y and by (1.5, 0, 0.5) rad, shifted by
# (2, 1, -2) cm, with initial_pose given and auto. Prints a Markdown table: per pose the mean
# vertex error over the sequence, the pose chosen, the first frame's time and the part of it
# that checked the given pose and searched (stats.csv t_prealign_ms).
#   tools/global_pose.sh [BUILD_DIR] [MESHES_DIR] [MODES]   # defaults: build, MESHES below,
#                                                          # "given auto"
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
MESHES=${2:-../shared/data/meshes}
MODES=${3:-given auto}
FEMREG=$BUILD/femreg
PYTHON=/usr/bin/python3
if [[ ! -x $FEMREG ]]; then
  echo "global_pose: $FEMREG not found; build first (bash tools/build.sh)" >&2
  exit 1
fi
if [[ ! -f $MESHES/creatures_bunny.msh ]]; then
  echo "global_pose: no $MESHES/creatures_bunny.msh (the public meshes' folder is the second argument)" >&2
  exit 1
fi
MESHES=$(cd "$MESHES" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# No anchors: nothing but the cloud says where the bunny is.
"$PYTHON" - tools/public_meshes/bunny.yaml "$work/synth.yaml" <<'PY'
import sys
text = open(sys.argv[1]).read()
start, end = text.index("anchors:"), text.index("synth:")
open(sys.argv[2], "w").write(text[:start] + text[end:])
PY
ln -s "$MESHES/creatures_bunny.msh" "$work/creatures_bunny.msh"
echo "== femreg synth" >&2
"$FEMREG" synth "$work/synth.yaml" --out "$work/seq" --no-progress > "$work/synth.log" 2>&1 || {
  tail -20 "$work/synth.log" >&2
  exit 1
}
poses=("aligned:0,0,0:0,0,0" "0.5 rad about y:0,0.5,0:0.02,0.01,-0.02"
       "1.2 rad about y:0,1.2,0:0.02,0.01,-0.02" "2.5 rad about y:0,2.5,0:0.02,0.01,-0.02"
       "(1.5, 0, 0.5) rad:1.5,0,0.5:0.02,0.01,-0.02")
echo "| rest pose | initial_pose | mean error (mm) | pose chosen | first frame (ms) | of which pose check and search (ms) | median frame (ms) |"
echo "|---|---|---|---|---|---|---|"
for entry in "${poses[@]}"; do
  IFS=: read -r name rotation translation <<< "$entry"
  for mode in $MODES; do
    out="$work/out_${mode}_${rotation//,/_}"
    echo "== $name, initial_pose $mode" >&2
    "$FEMREG" register --scene "$work/seq/scene.yaml" --frames "$work/seq/clouds" \
        --ground-truth "$work/seq/ground_truth" --out "$out" --no-progress \
        --set "objects[0].pose.rotation=[$rotation]" \
        --set "objects[0].pose.translation=[$translation]" \
        --set "registration.initial_pose=$mode" > "$out.log" 2>&1 || {
      tail -20 "$out.log" >&2
      exit 1
    }
    "$PYTHON" - "$out" "$name" "$mode" <<'PY'
import csv, json, os, sys
s = json.load(open(os.path.join(sys.argv[1], "summary.json")))
first = next(csv.DictReader(open(os.path.join(sys.argv[1], "stats.csv"))))
pose = s["initial_pose"]
chosen = pose["chosen"] + (" (ambiguous)" if pose["ambiguous"] else "")
print(f"| {sys.argv[2]} | {sys.argv[3]} | {s['vertex_error_mm']['mean']:.2f} | {chosen} | "
      f"{pose['first_frame_ms']:.0f} | {float(first['t_prealign_ms']):.0f} | "
      f"{s['ms_per_frame_median']:.0f} |")
PY
  done
done
