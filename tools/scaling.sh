#!/usr/bin/env bash
# Cost against size (docs/performance/scaling.md includes what this writes):
# bench/femreg_scaling_bench (box meshes of ~1k to ~64k vertices, clouds of 2k to 300k
# points, fast back end, one thread) into docs/scaling/: the benchmark's JSON, a CSV, a
# markdown table and a log-log plot. Builds the
# benchmarks in BUILD_DIR (default build-bench) if needed. Takes ~6 minutes on 2 cores (plus the build); run
# on a quiet machine.
#   tools/scaling.sh [BUILD_DIR] [--benchmark_filter=...]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build-bench}
shift || true
OUT=docs/scaling
if [[ ! -x "$BUILD/bench/femreg_scaling_bench" ]]; then
  if [[ -f "$BUILD/CMakeCache.txt" ]]; then  # an existing build: add the benchmarks to it
    cmake -S . -B "$BUILD" -DFEMREG_BUILD_BENCHMARKS=ON >/dev/null
  else
    cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DFEMREG_BUILD_BENCHMARKS=ON -DFEMREG_BUILD_TESTS=OFF \
      -DFEMREG_BUILD_PYTHON=OFF >/dev/null
  fi
  cmake --build "$BUILD" --target femreg_scaling_bench -j "$(nproc)"
fi
mkdir -p "$OUT"
"$BUILD/bench/femreg_scaling_bench" --benchmark_out="$OUT/scaling.json" --benchmark_out_format=json "$@"
# Debian's interpreter has matplotlib (tools/setup.sh installs python3-matplotlib).
"${FEMREG_PYTHON:-/usr/bin/python3}" tools/plot_scaling.py "$OUT/scaling.json" "$OUT"
