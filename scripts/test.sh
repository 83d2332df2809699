#!/usr/bin/env bash
# Runs every test: installs and builds what is missing first (scripts/setup.sh), then the
# C++ tests (ctest) and the Python tests (pytest; they start real servers on unique domains).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# stage NAME: a section header with the seconds since the start (setup included), so a slow CI run shows where.
stage() { echo "== $* (at ${SECONDS} s)"; }
"$ROOT/scripts/setup.sh"
BUILD="${SURFELEDIT_BUILD_DIR:-$ROOT/build}"
export SURFELEDIT_SERVER="$BUILD/server/app/surfeledit-server"
export SURFELEDIT_PROTO_ECHO="$BUILD/tests/surfeledit-proto-echo"
export SURFELEDIT_SECURE_PROBE="$BUILD/tests/surfeledit-secure-probe"
# Every test runs under a time limit, so a hang fails the run naming itself and the stacks it is stuck in, long before
# CI's own limit ends the job with nothing to read. ctest: 600 s per test (the slowest takes under 10 s here).
stage "C++ tests"
ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)" --timeout 600
# with_deadline SECONDS LOG CMD...: runs CMD with its output in LOG. Still running after SECONDS: prints every
# thread's stack (gdb) and LOG's last lines, kills it and fails. A watcher process sleeps beside it; nothing polls.
with_deadline() {
  local limit="$1" log="$2" pid watcher rc=0
  shift 2
  "$@" >"$log" 2>&1 &
  pid="$!"
  (
    # The sleep's output goes nowhere and the watcher ends it when it is itself ended: no process left holding CI's
    # output open.
    sleep "$limit" >/dev/null 2>&1 &
    local sleeper="$!"
    trap 'kill "$sleeper" 2>/dev/null; exit 0' TERM
    wait "$sleeper"
    kill -0 "$pid" 2>/dev/null || exit 0
    echo "'$*' still runs after ${limit} s: its threads' stacks, then the end of $log"
    gdb -p "$pid" -batch -ex "thread apply all bt" 2>&1 | grep -E "^(Thread|#)" | head -n 400
    tail -n 40 "$log"
    kill -9 "$pid"
  ) &
  watcher="$!"
  wait "$pid" || rc="$?"
  kill "$watcher" 2>/dev/null || true
  wait "$watcher" 2>/dev/null || true
  return "$rc"
}
# sanitizer_build NAME DIR CMAKE_OPTION TARGETS [EXTRA_CMAKE_ARGS...]: a separate instrumented build (no Python
# module, no benchmarks) of the given test targets in DIR; logs in $BUILD/setup-NAME-*.log. A unity build (CMake
# compiles up to eight sources of a target as one file; sources with flags of their own stay alone): about a third
# less compile time, since every instrumented file otherwise parses Eigen, the session API and gtest again. So
# helpers in anonymous namespaces need names unique across their target's files (docs/hardening.md §5).
sanitizer_build() {
  local name="$1" dir="$2" option="$3" targets="$4"
  shift 4
  if [ ! -f "$dir/CMakeCache.txt" ]; then
    cmake -S "$ROOT" -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-D$option=ON" -DCMAKE_UNITY_BUILD=ON \
      -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache \
      -DSURFELEDIT_BUILD_PYTHON=OFF -DSURFELEDIT_BUILD_BENCH=OFF "$@" >"$BUILD/setup-$name-configure.log" 2>&1 \
      || { tail -n 40 "$BUILD/setup-$name-configure.log"; exit 1; }
  fi
  # shellcheck disable=SC2086  # the targets are words
  cmake --build "$dir" -j "$(nproc)" --target $targets >"$BUILD/setup-$name-build.log" 2>&1 \
    || { "$ROOT/scripts/build_failed.sh" "$BUILD/setup-$name-build.log" "$dir"; exit 1; }
}

# Both instrumented builds compile with -O1 -g1: quicker to build than -O2 -g (-g1: line tables only, ~20 % less
# compile time, enough for the sanitizers' stack traces), still optimised enough to keep the tests fast.
SANITIZER_FLAGS=(-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1")

stage "ThreadSanitizer: background hierarchy rebuilds while steps run, the helpers of a step's loops"
# The suppression covers a load-time mutex misuse in libOpenNI2, which PCL pulls in (tests/tsan_suppressions.txt).
TSAN_BUILD="${SURFELEDIT_TSAN_BUILD_DIR:-$ROOT/build-tsan}"
export TSAN_OPTIONS="suppressions=$ROOT/tests/tsan_suppressions.txt halt_on_error=1"
sanitizer_build tsan "$TSAN_BUILD" SURFELEDIT_TSAN surfeledit_tsan_tests "${SANITIZER_FLAGS[@]}"
with_deadline 600 "$TSAN_BUILD/tsan-tests.log" "$TSAN_BUILD/tests/surfeledit_tsan_tests" \
  --gtest_filter='BvhRebuild.*:BvhUpdate.StatusFreshRefitRebuilding:CollisionBvh.BackgroundRebuildWhileStepsArrive:ShareChunks.*' \
  || { tail -n 60 "$TSAN_BUILD/tsan-tests.log"; exit 1; }
grep -E "^\[ rebuild \]|tests? from .* ran|PASSED" "$TSAN_BUILD/tsan-tests.log"
unset TSAN_OPTIONS

# AddressSanitizer and UndefinedBehaviorSanitizer in one build (they combine; one instrumented build instead of
# two keeps CI's cold build short): the service tests and most core tests
SANITIZED_TESTS="surfeledit_core_tests surfeledit_service_tests"
# The core tests except the slowest sweeps, which repeat code paths the rest covers on more data
# (this first group took ~80% of the instrumented run time before it was skipped; docs/hardening.md §5).
SANITIZER_SKIP="BvhTree.TreeTreeHasNoFalseNegativesEachRowOnce:*.ThreadsGiveIdenticalResults:ParticleStability.*"
SANITIZER_SKIP+=":*.NumericalExtremes:ApproximateDetection.*:BvhOverlap.FullSatIsExactAndLiteIsConservative"
SANITIZER_SKIP+=":CollisionBvh.EveryConfigurationEqualsNoHierarchyEveryStep:*.EqualsOracleEveryStep"
SANITIZER_SKIP+=":BvhUpdate.PropertyAllStrategiesWithInsertionsAndRemovals:Curves.AgainstTheExactIntersection"
SANITIZER_SKIP+=":Merge.AgainstExactTruth"
# Brute-force sweeps over many queries or steps (each 19-45 s instrumented, 163 s of the remaining 360 s).
SANITIZER_SKIP+=":KdTreeFromLeaf.TiesAcrossCutsThroughEqualCoordinates:KdTreeFromLeaf.TiesOnALatticeWithDuplicatesFromEveryStart"
SANITIZER_SKIP+=":CollisionTemporal.LeafStartEqualsTheRootDescentEveryStep:BvhBounded.CandidatesContainEveryOverlapEveryStep"
SANITIZER_SKIP+=":CollisionSimple.BoundaryMarksOnInterleavedRegionsFollowTheOracle:BvhBounded.HullPruningKeepsEveryOverlap"
# run_sharded LOG BINARY [ARGS...]: the binary's tests split over one process per core (at most 8: an instrumented
# process holds up to ~1 GB) that run at once (GoogleTest's sharding; an instrumented test binary keeps about one core
# busy), shard K's output in LOG-K.log, shown when it fails.
run_sharded() {
  local log="$1" shards k failed=0
  shift
  shards="$(nproc)"
  [ "$shards" -le 8 ] || shards=8
  local pids=()
  for ((k = 0; k < shards; k++)); do
    GTEST_TOTAL_SHARDS="$shards" GTEST_SHARD_INDEX="$k" with_deadline 1200 "$log-$k.log" "$@" &
    pids+=("$!")
  done
  for ((k = 0; k < shards; k++)); do
    if wait "${pids[k]}"; then
      grep -h "tests from .* ran" "$log-$k.log" | sed "s/^/shard $k: /"
    else
      failed=1
      echo "shard $k of $shards failed:"
      tail -n 60 "$log-$k.log"
    fi
  done
  return "$failed"
}
run_sanitized() {  # run_sanitized DIR: both test binaries, each test's name in the logs (a hang's log ends with it)
  run_sharded "$1/core-tests" "$1/tests/surfeledit_core_tests" --gtest_filter="-$SANITIZER_SKIP" || exit 1
  with_deadline 900 "$1/service-tests.log" "$1/tests/surfeledit_service_tests" \
    || { grep -E "^\[ +(RUN|FAILED) +\]" "$1/service-tests.log" | tail -n 3; tail -n 60 "$1/service-tests.log"; exit 1; }
}
stage "AddressSanitizer + UndefinedBehaviorSanitizer: service tests, core tests but the slowest sweeps"
SAN_BUILD="${SURFELEDIT_ASAN_BUILD_DIR:-$ROOT/build-asan}"
sanitizer_build asan "$SAN_BUILD" SURFELEDIT_ASAN "$SANITIZED_TESTS" -DSURFELEDIT_UBSAN=ON "${SANITIZER_FLAGS[@]}"
# Leak checking is off: OpenMP, PCL and Cyclone keep process-lifetime allocations it would list.
ASAN_OPTIONS="detect_leaks=0 abort_on_error=1" UBSAN_OPTIONS="print_stacktrace=1 halt_on_error=1" \
  run_sanitized "$SAN_BUILD"

stage "Python tests"
cd "$ROOT"
# Parallel workers (pytest-xdist): each test starts its own server on a domain that its process holds
# a lock on (tests/python/service/domains.py), so workers, other runs and benchmarks never meet on one.
# Two workers per core, at most 4: a worker spends about half its time waiting for its server's replies, so on
# the 2-core host 4 workers take 178 s where 2 took 272 s.
WORKERS="$((2 * $(nproc)))"
[ "$WORKERS" -le 4 ] || WORKERS=4
# 600 s per test (the slowest, the request fuzzer, takes ~50 s); past it the worker prints every thread's stack and ends, and the test fails.
PYTEST_LIMIT=(--timeout 600 --timeout-method thread)
"$ROOT/.venv/bin/python" -m pytest tests/python -q -rs -n "$WORKERS" "${PYTEST_LIMIT[@]}" "$@"

# The secured Python client (connect(security=...)) runs on the cyclonedds 0.10.2 binding of
# .venv-secure (scripts/setup.sh); under .venv those tests are skipped.
if [ -x "$ROOT/.venv-secure/bin/python" ]; then
  stage "Python tests with DDS Security (.venv-secure)"
  "$ROOT/.venv-secure/bin/python" -m pytest tests/python/security -q -rs "${PYTEST_LIMIT[@]}"
fi
stage "all tests passed"
