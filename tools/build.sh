#!/usr/bin/env bash
# Configures and builds lammps-kifmm into ./build (or $KIFMM_BUILD_DIR).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${KIFMM_BUILD_DIR:-$root/build}"
bash "$root/tools/setup.sh"
jobs="${KIFMM_JOBS:-$(nproc)}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release ${KIFMM_CMAKE_ARGS:-} >/dev/null
cmake --build "$build" -j "$jobs"
