#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# README command (b): install what is missing, build, run the engine's unit tests in an
# AddressSanitizer + UndefinedBehaviorSanitizer build, then the whole test suite with ctest
# (MPI tests run under mpirun --oversubscribe; root is allowed through OMPI's variables), then
# the plugin built against a current LAMMPS source tree and tested in that LAMMPS (when one is
# given or a source tarball is beside the checkout; otherwise a line says it is skipped)
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
     ctest --output-on-failure -j "${KIFMM_TEST_JOBS:-2}" -L engine -E "${KIFMM_ASAN_EXCLUDE:-Benchmark|CostRatio|ErrorFallsMonotonically|LaplaceNeutralMatchesEwald|DipolesAndClustersMatchEwald|ChosenLeafGivesTheModelsDepth|ChosenTreesMeetTheRequestedAccuracy|ChoiceFromClusteredPoints|ChoiceFromPointsPeriodic|GridOfStretchedCells}") \
    || status=1
fi

echo "== full test suite =="
(cd "$build" && ctest --output-on-failure -j "${KIFMM_TEST_JOBS:-2}" ${KIFMM_CTEST_ARGS:-}) || status=1

# The plugin in a current LAMMPS: built against a LAMMPS source tree and run in that LAMMPS
# (label current). The tree is LAMMPS_SOURCE_DIR=<lammps>/src with its build directory in
# KIFMM_LAMMPS_BINARY_DIR, or else a LAMMPS source tarball in ../shared/lammps/ beside the
# checkout (or KIFMM_LAMMPS_TARBALL), built once per machine by tools/build-lammps.sh.
tree="${LAMMPS_SOURCE_DIR:-}" lammps_bin="${KIFMM_LAMMPS_BINARY_DIR:-}"
if [ -z "$tree" ]; then
  tarball="${KIFMM_LAMMPS_TARBALL:-}"
  if [ -z "$tarball" ]; then
    for t in "$root"/../shared/lammps/lammps-*.tar.gz; do [ -f "$t" ] && tarball="$t"; done
  fi
  if [ -n "$tarball" ]; then
    echo "== current LAMMPS from $(basename "$tarball") =="
    if lammps_build=$(bash "$root/tools/build-lammps.sh" "$tarball" | tail -n 1); then
      tree="$lammps_build/source/src" lammps_bin="$lammps_build"
    else
      echo "build of the current LAMMPS failed"; status=1
    fi
  fi
fi
if [ -n "$tree" ]; then
  echo "== plugin in the current LAMMPS ($tree) =="
  current="${build}-current"
  cmake -S "$root" -B "$current" -DCMAKE_BUILD_TYPE=Release -DLAMMPS_SOURCE_DIR="$tree" \
        -DKIFMM_LAMMPS_BINARY_DIR="$lammps_bin" -DKIFMM_REFERENCE_LMP="$build/lmp_kifmm" >/dev/null \
    && cmake --build "$current" -j "${KIFMM_JOBS:-$(nproc)}" --target kifmmplugin \
    && (cd "$current" && ctest --output-on-failure -j "${KIFMM_TEST_JOBS:-2}" -L current) || status=1
else
  echo "== plugin in a current LAMMPS: skipped (no LAMMPS source tree: set LAMMPS_SOURCE_DIR=<lammps>/src" \
       "and KIFMM_LAMMPS_BINARY_DIR=<its build directory>, or put a LAMMPS source tarball in ../shared/lammps/) =="
fi
exit $status
