#!/usr/bin/env bash
# Installs what is missing, builds femreg with its tests and runs them through CTest: the
# GoogleTest executables and the Python package's pytest suite (python/tests, the CTest
# test python_tests, run on the module in the build tree).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
cd "${BUILD_DIR:-build}"
if ! ctest -N -R '^python_tests$' | grep -q 'Total Tests: 1'; then
  echo "test: the Python tests are not configured (pybind11-dev missing? see tools/setup.sh)" >&2
  exit 1
fi
ctest --output-on-failure -j "${JOBS:-$(nproc)}"
