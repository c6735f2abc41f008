#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Configures and builds lammps-kifmm into ./build (or $KIFMM_BUILD_DIR).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${KIFMM_BUILD_DIR:-$root/build}"
bash "$root/tools/setup.sh"
jobs="${KIFMM_JOBS:-$(nproc)}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release ${KIFMM_CMAKE_ARGS:-} >/dev/null
cmake --build "$build" -j "$jobs"
