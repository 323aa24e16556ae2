#!/usr/bin/env bash
# The embedded-surface benchmark (docs/guide/embedded-surfaces.md): a fine "scan" made from a
# public surface by Loop subdivision, a coarse cage around it (femreg mesh --cage), the scan
# tetrahedralized as it is (the fine mesh), a femreg synth sequence whose ground truth is the
# fine mesh, then the sequence tracked three ways: the cage carrying the scan, the fine mesh
# carrying the same scan (the same energy on the fine physics; its err_surface columns compare
# with the cage's: the scan's ground truth, ground_truth/surface/, serves both), the fine mesh
# alone (its time). Prints a table row per run and thread count.
#
# usage: tools/embedded_bench.sh FEMREG SURFACE.stl|.ply OUT [SCALE] [CAGE_VERTICES] [LEVELS]
#   SCALE (0.015): to metres; CAGE_VERTICES (1500); LEVELS (2): Loop subdivisions of the input
#   for the scan (x4 triangles each). The scan tracked by the cage may be finer than the one
#   tetrahedralized: FINE_LEVELS (default LEVELS) sets the latter. SQRT3 (0) and FINE_SQRT3
#   (default SQRT3): sqrt(3) subdivisions after the Loop levels (x3 triangles each; Bunny.stl
#   at LEVELS=1 SQRT3=2: 98,208 triangles). FRAMES (20): the synth sequence's length.
# The scene (camera, motion, clamp) is the bunny's: the input's +y is up, the base at its
# smallest y is clamped and the top (y > 0.05 m) pushed and turned. CLAMP_Y (-0.072 m): the
# clamp holds y below it (the armadillo at SCALE 0.01: -0.045). SPLIT=1 splits non-manifold
# vertices of the input first (subdivide_surface.py --split-nonmanifold). THREADS ("1 2"):
# the thread counts of the tracking runs.
set -euo pipefail
FEMREG=$(realpath "$1"); INPUT=$(realpath "$2"); OUT=$3
SCALE=${4:-0.015}; CAGE=${5:-1500}; LEVELS=${6:-2}; FINE_LEVELS=${FINE_LEVELS:-$LEVELS}
SQRT3=${SQRT3:-0}; FINE_SQRT3=${FINE_SQRT3:-$SQRT3}; FRAMES=${FRAMES:-20}
CLAMP_Y=${CLAMP_Y:--0.072}; THREADS=${THREADS:-1 2}
SPLIT_ARG=""; [ "${SPLIT:-0}" = 1 ] && SPLIT_ARG="--split-nonmanifold"
HERE=$(cd "$(dirname "$0")" && pwd)
PY=${PYTHON:-python3}
mkdir -p "$OUT"; cd "$OUT"
[ -f scan.ply ] || "$PY" "$HERE/subdivide_surface.py" "$INPUT" scan.ply --levels "$LEVELS" --sqrt3 "$SQRT3" --scale "$SCALE" $SPLIT_ARG
[ -f fine_scan.ply ] || "$PY" "$HERE/subdivide_surface.py" "$INPUT" fine_scan.ply --levels "$FINE_LEVELS" --sqrt3 "$FINE_SQRT3" --scale "$SCALE" $SPLIT_ARG
[ -f cage.vtu ] || "$FEMREG" mesh scan.ply --cage "$CAGE" --out cage.vtu > cage.log
[ -f fine.vtu ] || "$FEMREG" mesh fine_scan.ply --keep-surface --edge-length 0.006 --out fine.vtu > fine.log

scene() {  # scene MESH SURFACE(or "") > file
  local surface=""
  [ -n "$2" ] && surface="surface: $2"
  cat <<EOF
description: "a scan pushed and turned at the top, its base clamped"
objects:
  - name: body
    mesh: $1
    $surface
    material: {youngs_modulus: 50000, poisson_ratio: 0.35, density: 200}
boundary:
  - {select: {box: {min: [-1, -1, -1], max: [1, $CLAMP_Y, 1]}}, clamp: true}
forward: {max_iterations: 50}
registration:
  regularizer: corotational
  camera: {position: [0.05, 0.08, 0.33], target: [0, 0, 0], up: [0, 1, 0],
           fx: 262.5, fy: 262.5, cx: 159.5, cy: 119.5, width: 320, height: 240}
  data: {max_distance: 0.03, loss: huber, loss_scale: 0.005, metric: point_to_plane, visibility: true}
  weights: {elastic: 1, temporal: 1}
  solver: {backend: fast}
anchors:
  - {name: clamp, select: {box: {min: [-1, -1, -1], max: [1, $CLAMP_Y, 1]}}, hard: true}
synth:
  frames: $FRAMES
  seed: 1
  ground_truth: {mesh: fine.vtu}
  sensor: {noise_coefficient: 2.85e-3, grazing_angle_deg: 80, pixel_stride: 2}
  motion:
    - name: top
      select: {box: {min: [-1, 0.05, -1], max: [1, 1, 1]}}
      centre: [0, 0.06, 0]
      keyframes:
        - {frame: 0}
        - {frame: 10, translation: [0.025, -0.005, 0.01], rotation: [0, 0.3, 0]}
        - {frame: 19, translation: [-0.015, -0.01, 0.0], rotation: [0, -0.2, 0.1]}
EOF
}
scene cage.vtu scan.ply > cage.yaml
scene fine.vtu scan.ply > fine_embedded.yaml
scene fine.vtu "" > fine.yaml
[ -d seq ] || "$FEMREG" synth cage.yaml --out seq > synth.log

row() {  # row NAME SCENE THREADS
  rm -rf "run_$1_$3"
  local truth="--ground-truth seq/ground_truth"
  grep -q "surface:" "$2" || truth=""  # the mesh alone: its time
  "$FEMREG" register --scene "$2" --frames seq/clouds $truth \
    --out "run_$1_$3" --threads "$3" --no-progress > "run_$1_$3.log" 2>&1
  "$PY" - "run_$1_$3/stats.csv" "$1" "$3" <<'PY'
import csv, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
def mean(k):
    v = [float(r[k]) for r in rows if r.get(k) not in (None, "")]
    return st.mean(v) if v else float("nan")
t = [float(r["t_total_ms"]) for r in rows]
print(f"{sys.argv[2]:14s} threads {sys.argv[3]}  median {st.median(t):7.1f} ms  mean {st.mean(t):7.1f} ms  "
      f"surface err mean {mean('err_surface_mean_mm'):.3f} seen {mean('err_surface_seen_mean_mm'):.3f} "
      f"p95 {mean('err_surface_p95_mm'):.3f} mm  mesh err mean {mean('err_mean_mm'):.3f} mm  "
      f"outer {mean('outer_iterations'):.1f}")
PY
}
for threads in $THREADS; do
  row cage cage.yaml "$threads"
  row fine_embedded fine_embedded.yaml "$threads"
  row fine fine.yaml "$threads"
done
