#!/usr/bin/env bash
# Installs what is missing, builds femreg with its tests and runs them through CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
cd "${BUILD_DIR:-build}"
ctest --output-on-failure -j "${JOBS:-$(nproc)}"
