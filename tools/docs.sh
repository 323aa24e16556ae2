#!/usr/bin/env bash
# Builds femreg's documentation site (Sphinx + MyST, docs/) as HTML into OUT (default
# build/docs), offline, with warnings as errors. The Python API page imports the femreg
# module: from FEMREG_PYTHONPATH if set, else the build tree's (BUILD_DIR/python, default
# build/python, made by tools/build.sh), else the one tools/setup.sh installed. The C++ API
# pages (one per public header) are generated into docs/api/generated/ first.
#   tools/docs.sh [OUT]
# CTest runs it as the test `docs`. Debian packages: python3-sphinx, python3-myst-parser,
# python3-sphinx-rtd-theme (tools/setup.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-build/docs}
PYTHON=${FEMREG_PYTHON:-/usr/bin/python3}

if ! "$PYTHON" -c "import sphinx, myst_parser" 2>/dev/null; then
  echo "docs: Sphinx and MyST are missing for $PYTHON (Debian: python3-sphinx python3-myst-parser;" \
       "bash tools/setup.sh installs them)" >&2
  exit 1
fi

# The femreg module for the Python API page.
BUILD_DIR=${BUILD_DIR:-build}
if [[ -n "${FEMREG_PYTHONPATH:-}" ]]; then
  export PYTHONPATH="$FEMREG_PYTHONPATH${PYTHONPATH:+:$PYTHONPATH}"
elif [[ -f "$BUILD_DIR/python/femreg/__init__.py" ]]; then
  export PYTHONPATH="$(cd "$BUILD_DIR/python" && pwd)${PYTHONPATH:+:$PYTHONPATH}"
fi
if ! (cd / && "$PYTHON" -c "import femreg") 2>/dev/null; then
  echo "docs: the femreg Python module does not import (looked in ${FEMREG_PYTHONPATH:-$BUILD_DIR/python}" \
       "and $PYTHON's site directories): build it with bash tools/build.sh, install it with" \
       "bash tools/setup.sh, or point FEMREG_PYTHONPATH at the folder that holds femreg/" >&2
  (cd / && "$PYTHON" -c "import femreg") 2>&1 | tail -1 >&2 || true
  exit 1
fi

"$PYTHON" tools/docs_api_pages.py include/femreg docs/api/generated
mkdir -p "$OUT"
start=$(date +%s)
"$PYTHON" -m sphinx -b html -W --keep-going -q -d "$OUT/.doctrees" docs "$OUT"
echo "docs: $OUT/index.html ($(( $(date +%s) - start )) s)"
