#!/usr/bin/env bash
# Cost against size with an embedded surface (issue 41, item 5; docs/performance/embedded.md
# includes what this writes): the same clouds tracked by cages carrying scans of several sizes,
# (1) scans of 2.7k to 175k triangles on one cage, (2) one scan on cages of 250 to 4,000
# vertices. Per row: the median and mean time per frame, the correspondences' and the solve's
# share, the outer iterations, and, where the scan is the benchmark's own (its ground truth is in
# the sequence), the mean scan error.
#
# usage: tools/embedded_scaling.sh FEMREG BENCH_DIR INPUT [OUT_MD]
#   BENCH_DIR: a folder made by tools/embedded_bench.sh (its scan.ply, seq/clouds and
#   seq/ground_truth; e.g. LEVELS=1 SQRT3=2 for the 98k-triangle bunny scan); INPUT: the surface
#   it was made from (the other scans are made from it the same way); OUT_MD (default
#   docs/scaling/embedded.md). SCALE (0.015) as for embedded_bench.sh; CAGE (1500): the cage
#   of the surface sweep; THREADS ("1 2"); ROUNDS (3): every row is run once per round, each
#   frame's time the least over the rounds (another process's load only adds to a time). Run on a
#   quiet machine: about ten minutes; the table notes the load average before and after.
set -euo pipefail
FEMREG=$(realpath "$1"); BENCH=$(realpath "$2"); INPUT=$(realpath "$3")
HERE=$(cd "$(dirname "$0")" && pwd)
OUT_MD=$(realpath -m "${4:-$HERE/../docs/scaling/embedded.md}")
SCALE=${SCALE:-0.015}; CAGE=${CAGE:-1500}; THREADS=${THREADS:-1 2}; ROUNDS=${ROUNDS:-3}
PY=${PYTHON:-python3}
WORK="$BENCH/scaling"
mkdir -p "$WORK"; cd "$WORK"

# The scans: Loop levels 0-3 and the bench's own (scan.ply), by triangle count.
for spec in "L0 0 0" "L1 1 0" "L2 2 0" "L3 3 0"; do
  set -- $spec
  [ -f "scan_$1.ply" ] || "$PY" "$HERE/subdivide_surface.py" "$INPUT" "scan_$1.ply" --levels "$2" --sqrt3 "$3" --scale "$SCALE" > /dev/null
done
cp -f "$BENCH/scan.ply" scan_bench.ply
[ -f "cage_$CAGE.vtu" ] || "$FEMREG" mesh scan_bench.ply --cage "$CAGE" --out "cage_$CAGE.vtu" > "cage_$CAGE.log"
for n in 250 500 1000 2000 4000; do
  [ -f "cage_$n.vtu" ] || "$FEMREG" mesh scan_bench.ply --cage "$n" --out "cage_$n.vtu" > "cage_$n.log"
done

# The bench's scene with another cage and scan.
scene() {  # scene CAGE.vtu SCAN.ply > file
  sed -e "s|^    mesh: .*|    mesh: $1|" -e "s|^    surface: .*|    surface: $2|" -e "/^synth:/,$ d" "$BENCH/cage.yaml"
}
rows=rows.tsv
: > "$rows"
configs=()
for threads in $THREADS; do
  for scan in L0 L1 L2 bench L3; do configs+=("surface $CAGE $scan $threads"); done
  for n in 250 500 1000 "$CAGE" 2000 4000; do configs+=("cage $n bench $threads"); done
done
name_of() { echo "$1_$2_$3_$4"; }
run() {  # run SWEEP CAGE_N SCAN_NAME THREADS ROUND
  local name; name=$(name_of "$1" "$2" "$3" "$4")
  scene "cage_$2.vtu" "scan_$3.ply" > "$name.yaml"
  local truth=""
  [ "$3" = bench ] && truth="--ground-truth $BENCH/seq/ground_truth"
  rm -rf "run_${name}_$5"
  "$FEMREG" register --scene "$name.yaml" --frames "$BENCH/seq/clouds" $truth --out "run_${name}_$5" \
    --threads "$4" --no-progress > "run_${name}_$5.log" 2>&1
}
row() {  # row SWEEP CAGE_N SCAN_NAME THREADS: the table's row from the rounds' stats
  local name r stats=()
  name=$(name_of "$1" "$2" "$3" "$4")
  for r in $(seq 1 "$ROUNDS"); do stats+=("run_${name}_$r/stats.csv"); done
  "$PY" - "$1" "$2" "$3" "$4" "cage_$2.vtu" "scan_$3.ply" "${stats[@]}" >> "$rows" <<'PY'
import csv, statistics as st, sys
runs = [list(csv.DictReader(open(p))) for p in sys.argv[7:]]
rows = runs[0]
def count(path, word):  # vertices of a VTU ("NumberOfPoints") or triangles of a PLY
    head = open(path, "rb").read(4096).decode("latin-1")
    if word == "ply":
        return int(head.split("element face ")[1].split()[0])
    return int(head.split('NumberOfPoints="')[1].split('"')[0])
mean = lambda k: st.mean(float(r[k]) for r in rows if r.get(k) not in (None, ""))
least = lambda k: [min(float(run[f][k]) for run in runs) for f in range(len(rows))]
t = least("t_total_ms")
err = mean("err_surface_mean_mm") if sys.argv[3] == "bench" else float("nan")
print("\t".join(str(v) for v in [sys.argv[1], count(sys.argv[5], "vtu"), count(sys.argv[6], "ply"), sys.argv[4],
      f"{st.median(t):.1f}", f"{st.mean(t):.1f}", f"{st.mean(least('t_correspondences_ms')):.1f}",
      f"{st.mean(least('t_solve_ms')):.1f}", f"{mean('outer_iterations'):.2f}", f"{mean('model_to_cloud'):.0f}",
      f"{mean('cloud_to_model'):.0f}", f"{err:.3f}"]))
PY
}
load_before=$(cut -d" " -f1-3 /proc/loadavg)
# Round by round over every row: a change of the machine's load falls on all rows alike.
for r in $(seq 1 "$ROUNDS"); do
  for c in "${configs[@]}"; do run $c "$r"; done
done
for c in "${configs[@]}"; do row $c; done
load_after=$(cut -d" " -f1-3 /proc/loadavg)
"$PY" - "$rows" "$OUT_MD" "$(basename "$BENCH")" "$("$FEMREG" --version 2>/dev/null | head -1)" \
  "$ROUNDS" "$(nproc)" "$load_before" "$load_after" <<'PY'
import sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
head = ("| cage vertices | scan triangles | threads | median ms | mean ms | correspondences ms | solve ms "
        "| outer | model->cloud | cloud->model | scan error mm |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
def table(sweep):
    out = head
    for r in rows:
        if r[0] != sweep:
            continue
        err = "" if r[11] == "nan" else r[11]
        out += f"| {int(r[1]):,} | {int(r[2]):,} | {r[3]} | {r[4]} | {r[5]} | {r[6]} | {r[7]} | {r[8]} | {r[9]} | {r[10]} | {err} |\n"
    return out
md = ("<!-- written by tools/embedded_scaling.sh; do not edit -->\n\n"
      "**Surface size at a fixed cage**\n\n" + table("surface") +
      "\n**Cage size at a fixed scan**\n\n" + table("cage") +
      f"\nTimes per frame over the sequence `{sys.argv[3]}/seq` ({sys.argv[4] or 'femreg'}), each frame's "
      f"the least of {sys.argv[5]} runs; {sys.argv[6]} cores, load average {sys.argv[7]} before and "
      f"{sys.argv[8]} after. The scan error (mean over frames of the scan vertices' mean error) only where "
      "the scan is the sequence's own.\n")
open(sys.argv[2], "w").write(md)
print(md)
PY
