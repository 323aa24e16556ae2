#!/usr/bin/env bash
# Builds femreg's libFuzzer targets with clang and runs each for SECONDS_PER_TARGET seconds.
#
#   tools/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
#
# SECONDS_PER_TARGET defaults to 60 (the short run); the full campaign is 600 or more per
# target. TARGETs default to all: gmsh tetgen medit vtk_legacy vtu pcd ply xyz npy intrinsics
# tum scene.
# Environment: BUILD_DIR (default build-fuzz), JOBS (targets run side by side, default 1),
# FUZZ_ARGS (more libFuzzer flags). Seed corpora are made from datasets/ and tests/fixtures/;
# each target's corpus grows in BUILD_DIR/corpus/TARGET and is reused by the next run.
# A crash, hang (> 10 s), leak or out-of-memory input is written to BUILD_DIR/artifacts/TARGET/;
# keep each one in fuzz/regressions/TARGET/ (tests/fuzz_regression_test.cc replays them)
# once it is fixed. Exits non-zero when any target found one.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET="${1:-60}"
shift || true
ALL_TARGETS=(gmsh tetgen medit vtk_legacy vtu pcd ply xyz npy intrinsics tum scene)
TARGETS=("$@")
if [ $# -eq 0 ]; then TARGETS=("${ALL_TARGETS[@]}"); fi
BUILD_DIR="${BUILD_DIR:-build-fuzz}"
JOBS="${JOBS:-1}"

# Setup: clang and its libFuzzer runtime (Debian 12: clang 14, libclang-rt-14-dev), besides
# what tools/setup.sh installs for the normal build.
env -u BUILD_DIR bash tools/setup.sh >/dev/null  # its BUILD_DIR is the normal build's
missing=()
for p in clang libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "fuzz: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" != 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
CC=clang CXX=clang++ cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DFEMREG_BUILD_FUZZERS=ON -DFEMREG_BUILD_TESTS=OFF -DFEMREG_BUILD_TOOLS=OFF \
  "${launcher[@]}" >/dev/null
for t in "${TARGETS[@]}"; do  # only what is asked for: the scene target needs the whole library
  cmake --build "$BUILD_DIR" --target "fuzz_$t" -j "${BUILD_JOBS:-2}"
done

# Seed corpora from the bundled files (a sample of the many frames of each sequence).
seed() {  # seed TARGET FILE...
  local dir="$BUILD_DIR/corpus/$1"; shift
  mkdir -p "$dir"
  for f in "$@"; do cp -f "$f" "$dir/seed_$(echo "$f" | tr '/' '_')"; done
}
sample() {  # the first and every 8th file matching a find expression
  find datasets tests/fixtures fuzz/regressions "$@" -type f 2>/dev/null | sort | awk 'NR % 8 == 1'
}
mapfile -t msh < <(find tests/fixtures datasets -name '*.msh' -type f)
mapfile -t mesh < <(find tests/fixtures datasets -name '*.mesh' -type f)
mapfile -t vtk < <(find tests/fixtures datasets -name '*.vtk' -type f)
mapfile -t vtu < <(sample -name '*.vtu'; find tests/fixtures -name '*.vtu' -type f)
mapfile -t pcd < <(sample -name '*.pcd'; find tests/fixtures -name '*.pcd' -type f)
mapfile -t ply < <(find tests/fixtures datasets -name '*.ply' -type f)
mapfile -t xyz < <(find tests/fixtures datasets \( -name '*.xyz' -o -name '*.txt' \) -type f)
mapfile -t yaml < <(find datasets tests/fixtures -name '*.yaml' -type f)
mapfile -t npy < <(find tests/fixtures -name '*.npy' -type f)
mapfile -t json < <(find tests/fixtures -name '*.json' -type f)
mapfile -t tum < <(find tests/fixtures/camera/tum -name '*.txt' -type f)
seed gmsh "${msh[@]}"
seed medit "${mesh[@]}"
seed vtk_legacy "${vtk[@]}"
seed vtu "${vtu[@]}"
seed pcd "${pcd[@]}"
seed ply "${ply[@]}"
seed xyz "${xyz[@]}"
seed scene "${yaml[@]}"
seed npy "${npy[@]}"
seed intrinsics "${json[@]}"
seed tum "${tum[@]}"
mkdir -p "$BUILD_DIR/corpus/tetgen"
for node in $(find tests/fixtures datasets -name '*.node' -type f); do  # .node NUL .ele
  { cat "$node"; printf '\0'; cat "${node%.node}.ele"; } > "$BUILD_DIR/corpus/tetgen/seed_$(basename "$node")"
done
for t in "${ALL_TARGETS[@]}"; do  # the stored regressions seed their target too
  [ -d "fuzz/regressions/$t" ] && cp -f fuzz/regressions/"$t"/* "$BUILD_DIR/corpus/$t/" 2>/dev/null || true
done

run_one() {
  local t="$1" dir="$BUILD_DIR/corpus/$1" art="$BUILD_DIR/artifacts/$1/" log="$BUILD_DIR/logs/$1.log"
  rm -rf "$art"; mkdir -p "$art" "$(dirname "$log")"
  local dict=(); [ -f "fuzz/dicts/$t.dict" ] && dict=(-dict="fuzz/dicts/$t.dict")
  # -timeout: an input that takes 10 s is a hang; -rss_limit_mb: more than 2 GB is a bug
  # (no reader may size memory from a header alone).
  # VTK's XML reader leaks what it made when it refuses a corrupt file: fuzz/lsan_vtk.supp.
  LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan_vtk.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}" \
  "$BUILD_DIR/fuzz/fuzz_$t" "$dir" "${dict[@]}" -max_total_time="$SECONDS_PER_TARGET" \
    -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len=262144 \
    -artifact_prefix="$art" -print_final_stats=1 ${FUZZ_ARGS:-} > "$log" 2>&1 || true
}
export -f run_one
export BUILD_DIR SECONDS_PER_TARGET

echo "fuzz: ${#TARGETS[@]} target(s), ${SECONDS_PER_TARGET} s each, $JOBS at a time"
printf '%s\n' "${TARGETS[@]}" | xargs -P "$JOBS" -I{} bash -c 'run_one {}'

status=0
printf '%-11s %12s %8s %8s %8s\n' target executions corpus crashes hangs
for t in "${TARGETS[@]}"; do
  log="$BUILD_DIR/logs/$t.log"
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  corpus=$(find "$BUILD_DIR/corpus/$t" -type f | wc -l)
  crashes=$(find "$BUILD_DIR/artifacts/$t" -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'oom-*' \) | wc -l)
  hangs=$(find "$BUILD_DIR/artifacts/$t" -type f -name 'timeout-*' | wc -l)
  printf '%-11s %12s %8s %8s %8s\n' "$t" "${execs:-?}" "$corpus" "$crashes" "$hangs"
  if [ "$crashes" != 0 ] || [ "$hangs" != 0 ] || [ -z "$execs" ]; then status=1; fi
done
[ $status = 0 ] || echo "fuzz: see $BUILD_DIR/logs/ and $BUILD_DIR/artifacts/" >&2
exit $status
