#!/usr/bin/env bash
# Runs the hard-case suite (tests/hard_cases_test.cc, ctest label hard_cases) with both back
# ends and writes docs/hard_cases.md: per case and back end, the termination, the mean vertex
# error against the truth and that of doing nothing, the largest motion and the time per frame.
#   tools/hard_cases.sh [BUILD_DIR]      # default: build
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
TEST=$BUILD/tests/hard_cases_test
if [[ ! -x $TEST ]]; then
  echo "hard_cases: $TEST not found; build first (cmake --build $BUILD)" >&2
  exit 1
fi
csv=$(mktemp)
trap 'rm -f "$csv"' EXIT
status=0
FEMREG_HARD_CASES_CSV=$csv "$TEST" --gtest_brief=1 || status=$?
python3 - "$csv" "$status" > docs/hard_cases.md <<'PY'
import csv, sys, platform, subprocess
rows = list(csv.reader(open(sys.argv[1])))
status = int(sys.argv[2])
def num(v):
    return "–" if v in ("nan", "-nan") else v
print("# Hard cases\n")
print("Made by `tools/hard_cases.sh` from `tests/hard_cases_test.cc` (`ctest -L hard_cases`);")
print("on the machine's cores (`solver.threads` left at its default: femreg sets its own")
print("thread count, whatever `OMP_NUM_THREADS` says), so the times are comparable between rows,")
print("not with a loaded or a faster machine. Each case must end finite, bounded, and with a termination")
print("that says what happened; the test's assertions are in the source, next to each case.\n")
print("Errors are mean vertex distances (mm) to the truth after the last frame; *nothing* is the")
print("error of the rest shape (doing nothing). The beam is 0.2 x 0.04 x 0.04 m (10 x 2 x 2")
print("cells), clamped at x = 0, its end bent 20 mm down over three frames of 2000-point clouds")
print("covering the whole surface (0.2 mm noise), unless the case says otherwise.\n")
print("| case | back end | termination | error (mm) | nothing (mm) | max motion (mm) | ms/frame | message |")
print("|---|---|---|---|---|---|---|---|")
for r in rows:
    name, backend, term, err, nothing, motion, ms, msg = r[:8]
    print(f"| {name} | {backend} | {term} | {num(err)} | {num(nothing)} | {motion} | {ms} | {msg} |")
print()
print("Test result: " + ("all passed." if status == 0 else f"FAILED (exit {status}); see the test output."))
PY
echo "wrote docs/hard_cases.md ($(($(wc -l < "$csv"))) rows)"
exit $status
