#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# valgrind memcheck of a short lmp_kifmm run with kspace kifmm, fix kifmm/stride and
# fix clump/rigid (bench/soak/in.soak, small: 20 dipole clumps + 10 charged spheres, 200
# steps, then write_restart, clear, read_restart, 100 more steps with the restored clumps and
# stride cache, write_data).
#
#   bash tools/valgrind-check.sh [LMP_KIFMM]
#
# valgrind cannot run AVX-512 code, so without LMP_KIFMM the script builds lmp_kifmm with
# KIFMM_NATIVE=OFF (and -g1 for stack traces) in ${KIFMM_BUILD_DIR:-build}-valgrind first.
# Suppressions: tools/valgrind.supp (Open MPI's MPI_Init/Finalize allocations, the engine's
# process-wide FFTW plans; leak reports only, each justified there).
# Exit status 1 on any memcheck error (invalid access, uninitialised value, definite or
# possible leak). ctest: valgrind.short_run (label valgrind, registered with
# -DKIFMM_VALGRIND_TEST=ON).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
lmp="${1:-}"
if [ -z "$lmp" ]; then
  build="${KIFMM_BUILD_DIR:-$root/build}-valgrind"
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS=-g1 \
        -DKIFMM_NATIVE=OFF >/dev/null
  cmake --build "$build" -j "${KIFMM_JOBS:-$(nproc)}" --target lmp_kifmm >/dev/null
  lmp="$build/lmp_kifmm"
fi
work="$(mktemp -d "${TMPDIR:-/tmp}/kifmm-valgrind.XXXXXX")"
log="$work/valgrind.log"
cmd=(valgrind --error-exitcode=1 --leak-check=full --num-callers=50
     --suppressions="$root/tools/valgrind.supp" --log-file="$log"
     "$lmp" -in "$root/bench/soak/in.soak" -log "$work/log.lammps" -screen none
     -var steps 200 -var segments 2 -var NC 20 -var NF 10 -var restart 1
     -var rfile "$work/soak.restart" -var potentials "$root/potentials")
echo "command: OMP_NUM_THREADS=1 ${cmd[*]}"
start=$(date +%s)
status=0
(cd "$work" && OMP_NUM_THREADS=1 "${cmd[@]}") || status=$?
echo "wall time $(( $(date +%s) - start )) s, log $log"
grep -E "ERROR SUMMARY|definitely lost:|indirectly lost:|possibly lost:|still reachable:|suppressed:" "$log" \
  | sed 's/^==[0-9]*== *//'
grep -q "SOAK restarted" "$work/log.lammps" || { echo "the run did not reach its end"; status=1; }
if [ "$status" -ne 0 ]; then
  echo "valgrind-check: FAILED (exit status $status); first reports:"
  grep -m 40 -A 12 -E "Invalid|uninitialised|Conditional jump|definitely lost in|possibly lost in" "$log" || true
  exit 1
fi
echo "valgrind-check: clean"
