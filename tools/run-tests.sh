#!/usr/bin/env bash
# README command (b): install what is missing, build, run the whole test suite with ctest
# (MPI tests run under mpirun --oversubscribe; root is allowed through OMPI's variables).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${KIFMM_BUILD_DIR:-$root/build}"
bash "$root/tools/build.sh"
cd "$build"
ctest --output-on-failure -j "${KIFMM_TEST_JOBS:-2}" ${KIFMM_CTEST_ARGS:-}
