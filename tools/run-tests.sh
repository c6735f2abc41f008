#!/usr/bin/env bash
# README command (b): install what is missing, build, run the engine's unit tests in an
# AddressSanitizer + UndefinedBehaviorSanitizer build, then the whole test suite with ctest
# (MPI tests run under mpirun --oversubscribe; root is allowed through OMPI's variables)
# (skip that stage with KIFMM_SKIP_SANITIZERS=1; the slowest accuracy/cost tests, which run in
# the Release suite, are left out of it to keep CI short).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${KIFMM_BUILD_DIR:-$root/build}"
bash "$root/tools/build.sh"

status=0
if [ "${KIFMM_SKIP_SANITIZERS:-0}" != "1" ]; then
  echo "== engine unit tests under ASan + UBSan =="
  asan="${build}-asan"
  cmake -S "$root" -B "$asan" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS=-g1 -DKIFMM_ENGINE_ONLY=ON \
        -DKIFMM_SANITIZE=ON -DKIFMM_BUILD_BENCH=OFF >/dev/null
  cmake --build "$asan" -j "${KIFMM_JOBS:-$(nproc)}"
  (cd "$asan" && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
     LSAN_OPTIONS=suppressions="$root/tools/lsan.supp":print_suppressions=0 \
     UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 OMP_NUM_THREADS=2 OMP_WAIT_POLICY=PASSIVE \
     ctest --output-on-failure -j "${KIFMM_TEST_JOBS:-2}" -L engine -E "${KIFMM_ASAN_EXCLUDE:-Benchmark|CostRatio|ErrorFallsMonotonically|LaplaceNeutralMatchesEwald|DipolesAndClustersMatchEwald|ChosenLeafGivesTheModelsDepth|ChosenTreesMeetTheRequestedAccuracy|ChoiceFromClusteredPoints|ChoiceFromPointsPeriodic}") \
    || status=1
fi

echo "== full test suite =="
cd "$build"
ctest --output-on-failure -j "${KIFMM_TEST_JOBS:-2}" ${KIFMM_CTEST_ARGS:-} || status=1
exit $status
