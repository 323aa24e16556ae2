#!/usr/bin/env bash
# Robustness to sensor artefacts: makes two bundled sequences (datasets/beam_bend: a beam
# above a table, depth edges against it; datasets/block_press: a block on a table, concave
# corners) with `femreg synth`, clean, with each artefact of `femreg synth --artefact` at three
# strengths, and with all of them on at their realistic strengths (and without each in turn);
# registers every variant with the dataset's tracking scene (unchanged: nothing is tuned to
# the artefacts) on one thread and prints a Markdown table: sequence, artefact, strength, mean
# vertex error seen / hidden (mm), the seen error over the clean run's (seen / hidden), ms per
# frame (median).
#
#   tools/artefacts.sh [BUILD_DIR [OUT_DIR]]        (defaults: build, out/artefacts)
#   JOBS=2 tools/artefacts.sh build                  (two variants at once, each on one thread)
#   WRITE=1 tools/artefacts.sh build                 (also put the table in the docs page)
#
# 86 variants of 24 frames: about 12 minutes with JOBS=2 on a busy 2-core machine, most of it
# making the data; again on data already made, under 2 minutes.
# It can be stopped and started again: a variant's generated data are kept while its synth
# options are the same (FRESH=1 makes them all again, e.g. after a change to `femreg synth`),
# and a registration is skipped while its summary.json is newer than the binary and the data.
# So after a rebuild the same command registers every variant again on the data already made.
# A variant that fails is reported in the table and the others go on; the exit code is then 1.
# The table goes to OUT_DIR/table.md; with WRITE=1 it also replaces the table between the
# markers of docs/accuracy/robustness.md.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
FEMREG=$(realpath "$BUILD")/femreg
OUT=${2:-out/artefacts}
JOBS=${JOBS:-1}
[ -x "$FEMREG" ] || { echo "artefacts.sh: no femreg binary at $FEMREG (build the femreg_cli target)" >&2; exit 2; }
mkdir -p "$OUT"
# One thread: the same numbers on every machine, and timings that do not fight other jobs.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1

# run SEQUENCE NAME [--artefact SPEC ...]: generate (unless made already with these options),
# register (unless done by this binary on these data), keep the summary. Failures leave
# OUT/SEQUENCE/NAME/failed with the reason and return 0, so the other variants still run.
run() {
  local sequence=$1 name=$2
  shift 2
  local dir="$OUT/$sequence/$name"
  mkdir -p "$dir"
  rm -f "$dir/failed"
  local args="datasets/$sequence/synth.yaml $*"
  if [ ! -f "$dir/data/done" ] || [ "$(cat "$dir/data/done")" != "$args" ] || [ "${FRESH:-0}" = 1 ]; then
    rm -rf "$dir/data" "$dir/run"
    if ! "$FEMREG" synth "datasets/$sequence/synth.yaml" --out "$dir/data" --no-progress "$@" \
      > "$dir/synth.txt" 2>&1; then
      echo "synth failed: see $dir/synth.txt" > "$dir/failed"
      return 0
    fi
    echo "$args" > "$dir/data/done"
  fi
  if [ -f "$dir/run/summary.json" ] && [ "$dir/run/summary.json" -nt "$FEMREG" ] \
    && [ "$dir/run/summary.json" -nt "$dir/data/done" ]; then
    return 0
  fi
  rm -rf "$dir/run"
  if ! "$FEMREG" register --scene "$dir/data/scene.yaml" --frames "$dir/data/clouds" \
    --ground-truth "$dir/data/ground_truth" --out "$dir/run" --threads 1 --no-progress \
    --report none > "$dir/register.txt" 2>&1; then
    echo "register failed: see $dir/register.txt" > "$dir/failed"
  fi
  return 0
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
# One line per variant: sequence artefact strength name [synth options...]
VARIANTS=()
for sequence in beam_bend block_press; do
  VARIANTS+=("$sequence clean - clean")
  for sweep in "${SWEEPS[@]}"; do
    read -r artefact strengths <<< "$sweep"
    for strength in $strengths; do
      VARIANTS+=("$sequence $artefact $strength ${artefact}_$strength --artefact $artefact=$strength")
    done
  done
  # Every artefact at its realistic strength; then without each of them in turn (what each adds
  # to the others), and without both the flying pixels and the flicker.
  VARIANTS+=("$sequence all realistic all --artefact all")
  for sweep in "${SWEEPS[@]}"; do
    read -r artefact _ <<< "$sweep"
    name=all_but_$artefact
    [ "$artefact" = flying_pixels ] && name=all_but_flying  # the folder earlier runs made
    VARIANTS+=("$sequence all_but_$artefact realistic $name --artefact all --artefact $artefact=0")
  done
  VARIANTS+=("$sequence all_but_flying_pixels_flicker realistic all_but_flying_flicker --artefact all --artefact flying_pixels=0 --artefact flicker=0")
done

total=${#VARIANTS[@]}
i=0
for variant in "${VARIANTS[@]}"; do
  i=$((i + 1))
  read -r sequence _artefact _strength name options <<< "$variant"
  echo "[$i/$total] $sequence $name" >&2
  # shellcheck disable=SC2086  # the options are words
  run "$sequence" "$name" $options &
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n || true; done
done
wait

printf '%s\n' "${VARIANTS[@]}" > "$OUT/rows.txt"
status=0
/usr/bin/python3 - "$OUT" > "$OUT/table.md" <<'PY' || status=1
import json
import os
import sys

out = sys.argv[1]
rows = [line.split()[:4] for line in open(f"{out}/rows.txt") if line.strip()]


def summary(name):
    path = f"{out}/{name}/run/summary.json"
    if os.path.exists(f"{out}/{name}/failed") or not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def ratio(a, b):
    return f"{a / b:.2f}" if b else "-"


print("| sequence | artefact | strength | mean error seen / hidden (mm) "
      "| over clean: seen / hidden | ms/frame |")
print("|---|---|---:|---|---|---:|")
failed = False
for sequence, artefact, strength, name in rows:
    s = summary(f"{sequence}/{name}")
    c = summary(f"{sequence}/clean")
    if s is None or c is None:
        failed = True
        print(f"| {sequence} | {artefact} | {strength} | failed | | |")
        continue
    e = s["vertex_error_mm"]
    ce = c["vertex_error_mm"]
    print(f"| {sequence} | {artefact} | {strength} | {e['seen_mean']:.2f} / {e['hidden_mean']:.2f} "
          f"| {ratio(e['seen_mean'], ce['seen_mean'])} / {ratio(e['hidden_mean'], ce['hidden_mean'])} "
          f"| {s['ms_per_frame_median']:.0f} |")
sys.exit(1 if failed else 0)
PY
cat "$OUT/table.md"
if [ "${WRITE:-0}" = 1 ]; then
  /usr/bin/python3 - "$OUT/table.md" docs/accuracy/robustness.md <<'PY'
import sys

table, page = sys.argv[1], sys.argv[2]
start, end = "<!-- tools/artefacts.sh: table start -->", "<!-- tools/artefacts.sh: table end -->"
text = open(page).read()
if start not in text or end not in text:
    sys.exit(f"{page}: the markers {start!r} and {end!r} are missing")
head, rest = text.split(start, 1)
_, tail = rest.split(end, 1)
open(page, "w").write(head + start + "\n\n" + open(table).read() + "\n" + end + tail)
print(f"wrote the table into {page}", file=sys.stderr)
PY
fi
for variant in "${VARIANTS[@]}"; do
  read -r sequence _ _ name _ <<< "$variant"
  if [ -f "$OUT/$sequence/$name/failed" ]; then
    echo "failed: $sequence/$name: $(cat "$OUT/$sequence/$name/failed")" >&2
    status=1
  fi
done
exit $status
