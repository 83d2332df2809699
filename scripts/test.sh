#!/usr/bin/env bash
# Runs every test: installs and builds what is missing first (scripts/setup.sh), then the
# C++ tests (ctest) and the Python tests (pytest; they start real servers on unique domains).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$ROOT}"
BUILD="${SURFELEDIT_BUILD_DIR:-$ROOT/build}"
export SURFELEDIT_SERVER="$BUILD/server/app/surfeledit-server"
export SURFELEDIT_PROTO_ECHO="$BUILD/tests/surfeledit-proto-echo"
echo "== C++ tests"
ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)"
echo "== ThreadSanitizer: background hierarchy rebuilds while steps run"
# A separate instrumented build of the core tests (no Python module); the suppression covers a
# load-time mutex misuse in libOpenNI2, which PCL pulls in (tests/tsan_suppressions.txt).
TSAN_BUILD="${SURFELEDIT_TSAN_BUILD_DIR:-$ROOT/build-tsan}"
export TSAN_OPTIONS="suppressions=$ROOT/tests/tsan_suppressions.txt halt_on_error=1"
if [ ! -f "$TSAN_BUILD/CMakeCache.txt" ]; then
  cmake -S "$ROOT" -B "$TSAN_BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSURFELEDIT_TSAN=ON \
    -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache \
    -DSURFELEDIT_BUILD_PYTHON=OFF -DSURFELEDIT_BUILD_BENCH=OFF >"$BUILD/setup-tsan-configure.log" 2>&1 \
    || { tail -n 40 "$BUILD/setup-tsan-configure.log"; exit 1; }
fi
cmake --build "$TSAN_BUILD" -j "$(nproc)" --target surfeledit_core_tests >"$BUILD/setup-tsan-build.log" 2>&1 \
  || { grep -E "error|Error" "$BUILD/setup-tsan-build.log" | head -n 40; exit 1; }
"$TSAN_BUILD/tests/surfeledit_core_tests" \
  --gtest_filter='BvhRebuild.*:BvhUpdate.StatusFreshRefitRebuilding:CollisionBvh.BackgroundRebuildWhileStepsArrive' \
  --gtest_brief=1
unset TSAN_OPTIONS

echo "== Python tests"
cd "$ROOT"
"$ROOT/.venv/bin/python" -m pytest tests/python -q -rs "$@"
