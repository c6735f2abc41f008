#!/bin/bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Strong scaling of the distributed evaluation (doc/scaling.md):
#   bash bench/scaling/run_scaling.sh [build dir] [max N]
# 1 and 2 ranks x 1 and 2 threads at N = 1e5 and 1e6 (uniform, order 6, 3 timed evaluations
# after a warm-up), then bytes sent per rank for P = 1..8 (oversubscribed: only the bytes and
# ghost counts mean something there, not the times), also with periodic boundaries, and the
# locally essential trees below coarse frontier cells (top level forced to 2 and 3: frontier
# cells much larger than leaves; KIFMM_BASE_BUILD=dir also runs a build of another commit
# there, for comparison). Appends JSON lines to bench/scaling/results/scaling.jsonl (one per
# measurement, with its provenance).
# KIFMM_SCALING_ONLY=dipoles runs only the point-dipole cases: the
# same points with a charge and a moment each, and with charges only, on 1-8 ranks (open,
# periodic octree and grid).
set -e
cd "$(dirname "$0")/../.."
B=${1:-build}
NMAX=${2:-1e6}
OUT=bench/scaling/results/scaling.jsonl
mkdir -p bench/scaling/results
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
run() {
  local np=$1 th=$2 tag=$3
  shift 3
  OMP_NUM_THREADS=$th nice -n 10 mpirun --bind-to none --oversubscribe -np "$np" -x OMP_NUM_THREADS \
    "${BIN:-$B}/bench/scaling/bench_scaling" "$@" | sed "s/}\$/, \"tag\": \"$tag\"}/" | tee -a "$OUT"
}
Ns="1e5"
[ "$NMAX" = "1e6" ] && Ns="1e5 1e6"
if [ "${KIFMM_SCALING_ONLY:-}" = "dipoles" ]; then
  # point dipoles (every point a charge and a moment) against charges only: bytes and ghosts
  # per rank, open and periodic (octree and the single-level grid)
  for np in 1 2 4 8; do
    for what in charges dipoles; do
      run "$np" 1 "$what" 1e5 uniform 6 1 0 - "$what"
      run "$np" 1 "$what-periodic" 1e5 periodic 6 1 0 - "$what"
      run "$np" 1 "$what-periodic-grid" 1e5 periodic 6 1 0 grid=8 "$what"
    done
  done
  exit 0
fi
if [ "${KIFMM_SCALING_ONLY:-}" = "let" ]; then
  commit=$(git rev-parse --short HEAD)
  for N in $Ns; do
    for np in 2 3 4 8; do
      for top in 2 3 0; do
        run "$np" 1 "let-$commit" "$N" uniform 6 1 "$top"
        [ -n "${KIFMM_BASE_BUILD:-}" ] && BIN="$KIFMM_BASE_BUILD" run "$np" 1 "whole-cells-${KIFMM_BASE_TAG:-base}" "$N" uniform 6 1 "$top"
      done
    done
  done
  exit 0
fi
for N in $Ns; do
  for np in 1 2; do
    for th in 1 2; do run "$np" "$th" strong "$N" uniform 6 3; done
  done
done
for N in $Ns; do
  for np in 3 4 6 8; do run "$np" 1 bytes "$N" uniform 6 1; done
  run 8 1 bytes "$N" plummer 7 1
done
run 1 1 bytes 1e5 plummer 7 1
# periodic boundaries ([-1,1]^3 is the periodic cell): bytes and ghosts per rank, 1-8 ranks
for np in 1 2 3 4 6 8; do run "$np" 1 bytes-periodic 1e5 periodic 6 1; done
if [ "$NMAX" = "1e6" ]; then
  for np in 2 4 8; do run "$np" 1 bytes-periodic 1e6 periodic 6 1; done
fi
