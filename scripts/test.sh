#!/usr/bin/env bash
# Runs every test: installs and builds what is missing first (scripts/setup.sh), then the
# C++ tests (ctest) and the Python tests (pytest; they start real servers on unique domains).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
BUILD="${SURFELEDIT_BUILD_DIR:-$ROOT/build}"
export SURFELEDIT_SERVER="$BUILD/server/app/surfeledit-server"
export SURFELEDIT_PROTO_ECHO="$BUILD/tests/surfeledit-proto-echo"
echo "== C++ tests"
ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)"
echo "== Python tests"
cd "$ROOT"
"$ROOT/.venv/bin/python" -m pytest tests/python -q -rs "$@"
