#!/usr/bin/env bash
# The global initial pose from random poses (registration.initial_pose: auto) on the asymmetric
# public meshes: for each scene of tools/public_meshes/ (the cylinder left out: its turns about
# its axis are all alike) without its anchors, a femreg synth sequence; then its first frame
# registered alone from N rest poses, each turned by a rotation drawn uniformly (unit
# quaternions, numpy's default_rng(1)) and shifted by up to 3 cm per axis. A pose is found when
# the first frame's mean vertex error is within max(2x, +0.5 mm) of the aligned start's.
# Prints a Markdown table: per mesh the poses found, those reported ambiguous, the errors and
# the first frame's time (summary.json initial_pose.first_frame_ms).
#   tools/random_poses.sh [BUILD_DIR] [MESHES_DIR] [N] [NAMES]
#   defaults: build, ../shared/data/meshes, 20 per mesh (100 in all), "bunny armadillo raptor liver octopus"
# WRITE=1 also writes the table to docs/accuracy/random_poses.md (the performance pages').
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
MESHES=${2:-../shared/data/meshes}
N=${3:-20}
NAMES=${4:-bunny armadillo raptor liver octopus}
FEMREG=$(realpath "$BUILD/femreg")
PYTHON=/usr/bin/python3
if [[ ! -x $FEMREG ]]; then
  echo "random_poses: $FEMREG not found; build first (bash tools/build.sh)" >&2
  exit 1
fi
if [[ ! -d $MESHES ]]; then
  echo "random_poses: no folder $MESHES (the public meshes; pass their folder as the second argument)" >&2
  exit 1
fi
MESHES=$(cd "$MESHES" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
main() {
"$PYTHON" - "$N" > "$work/poses.txt" <<'PY'
import sys
import numpy as np
rng = np.random.default_rng(1)
for _ in range(int(sys.argv[1])):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    angle = 2 * np.arccos(min(1.0, abs(q[0])))
    axis = q[1:] / np.linalg.norm(q[1:]) * (1 if q[0] >= 0 else -1)
    t = rng.uniform(-0.03, 0.03, 3)
    print(",".join(f"{v:.5f}" for v in axis * angle), ",".join(f"{v:.4f}" for v in t))
PY
echo "| mesh | vertices | poses | found | ambiguous | aligned error (mm) | error when found, median (mm) | worst error (mm) | first frame, mean / max (ms) |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for name in $NAMES; do
  scene=tools/public_meshes/$name.yaml
  [[ -f $scene ]] || { echo "random_poses: no $scene" >&2; exit 1; }
  dir=$work/$name
  mkdir -p "$dir"
  # No anchors: nothing but the cloud says where the body is; two frames are enough.
  "$PYTHON" - "$scene" "$dir/synth.yaml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
start, end = text.index("anchors:"), text.index("synth:")
text = text[:start] + text[end:]
text = re.sub(r"(\n  frames:) *\d+", r"\1 2", text, count=1)
open(sys.argv[2], "w").write(text)
PY
  mesh=$(sed -n 's/^ *mesh: *\([^ ]*\).*/\1/p' "$scene" | head -1)
  ln -s "$MESHES/$mesh" "$dir/$mesh"
  echo "== $name: femreg synth" >&2
  "$FEMREG" synth "$dir/synth.yaml" --out "$dir/seq" --no-progress > "$dir/synth.log" 2>&1 || {
    tail -20 "$dir/synth.log" >&2
    exit 1
  }
  mkdir -p "$dir/one"
  first=$(ls "$dir/seq/clouds" | head -1)
  ln -s "$dir/seq/clouds/$first" "$dir/one/$first"
  run() {  # run OUT ROTATION TRANSLATION -> the run's summary.json
    "$FEMREG" register --scene "$dir/seq/scene.yaml" --frames "$dir/one" \
        --ground-truth "$dir/seq/ground_truth" --out "$1" --force --no-progress --threads 1 \
        --set "objects[0].pose.rotation=[$2]" --set "objects[0].pose.translation=[$3]" \
        --set registration.initial_pose=auto > "$1.log" 2>&1 || { tail -20 "$1.log" >&2; exit 1; }
  }
  run "$dir/aligned" 0,0,0 0,0,0
  k=0
  : > "$dir/results.txt"
  while read -r rotation translation; do
    k=$((k + 1))
    echo "== $name: pose $k of $N" >&2
    run "$dir/pose" "$rotation" "$translation"
    "$PYTHON" - "$dir/pose/summary.json" >> "$dir/results.txt" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
p = s["initial_pose"]
print(s["vertex_error_mm"]["mean"], int(p["ambiguous"]), p["first_frame_ms"], s["objects"][0]["vertices"])
PY
  done < "$work/poses.txt"
  "$PYTHON" - "$dir/aligned/summary.json" "$dir/results.txt" "$name" <<'PY'
import json, statistics, sys
aligned = json.load(open(sys.argv[1]))["vertex_error_mm"]["mean"]
rows = [line.split() for line in open(sys.argv[2]) if line.strip()]
errors = [float(r[0]) for r in rows]
ambiguous = sum(int(r[1]) for r in rows)
ms = [float(r[2]) for r in rows]
limit = max(2 * aligned, aligned + 0.5)
found = [e for e in errors if e <= limit]
median_found = f"{statistics.median(found):.2f}" if found else "-"
print(f"| {sys.argv[3]} | {rows[0][3]} | {len(rows)} | {len(found)} | {ambiguous} | {aligned:.2f} | "
      f"{median_found} | {max(errors):.1f} | {statistics.mean(ms):.0f} / {max(ms):.0f} |")
PY
done
}

main | tee "$work/table.md"
# Only a complete table replaces the page's (set -o pipefail: a failed run stops above).
if [[ ${WRITE:-0} == 1 ]]; then
  { echo "<!-- written by tools/random_poses.sh; do not edit -->"; echo; cat "$work/table.md"; } \
    > docs/accuracy/random_poses.md
  echo "random_poses: wrote docs/accuracy/random_poses.md" >&2
fi
