#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Tree choice measured in one process (bench_engine --tree-choice, see bench/bench_engine.cpp):
# per point set and order, the old per-order leaf size, the uniform-points cost model
# (choose_tree(order, n, periodic)) and the choice from the actual trees of the points
# (choose_tree(kernel, options, n, xyz)), timed interleaved on one thread; prints a markdown
# table (stdout) and the modelled against measured times (stderr).
#   bench/run_tree_choice.sh [BUILD_DIR] [extra bench_engine options]
# BUILD_DIR (default: build/ of this checkout, or $KIFMM_BUILD_DIR) must hold bench/bench_engine
# and bench_solvers (for the clustered data files of the bench/solvers campaign, written to
# $BUILD_DIR/tree_choice_data). The first line of the output is the provenance (commit, date,
# load average): keep it with the table in bench/results/.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-${KIFMM_BUILD_DIR:-$ROOT/build}}
shift || true
DATA="$BUILD/tree_choice_data"
mkdir -p "$DATA"
gen() {    # name n config [args]: the same generator and seed as bench/solvers/run_bench.py
  local name=$1 n=$2 cfg=$3
  shift 3
  [ -f "$DATA/${name}_$n.data" ] || "$BUILD/bench_solvers" gen --config "$cfg" --n "$n" --seed 1 \
    --out "$DATA/${name}_$n.data" "$@" >/dev/null
}
gen platelets 8752 clumps --mol "$ROOT/potentials/platelet_n14.mol" --pebble-radius 0.008
gen platelets 70016 clumps --mol "$ROOT/potentials/platelet_n14.mol" --pebble-radius 0.008
gen collapse 10000 plummer --a 0.005
gen collapse 100000 plummer --a 0.005
gen plummer 10000 plummer --a 0.05
gen plummer 100000 plummer --a 0.05
gen dipole3 99999 clumps --mol "$ROOT/potentials/dipole3.mol" --pebble-radius 0.005
files=$(ls "$DATA"/plummer_10000.data "$DATA"/plummer_100000.data "$DATA"/collapse_10000.data \
  "$DATA"/collapse_100000.data "$DATA"/platelets_8752.data "$DATA"/platelets_70016.data \
  "$DATA"/dipole3_99999.data | paste -sd,)
echo "commit $(git -C "$ROOT" rev-parse --short HEAD), $(date -u '+%Y-%m-%d %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
OMP_NUM_THREADS=1 nice -n 10 "$BUILD/bench/bench_engine" --tree-choice --sizes 1e3,3e3,1e4,1e5 --plummer "" \
  --data "$files" --orders 3,6,9,12 --reps 5 --min-time 0.2 "$@"
echo "load after $(cut -d' ' -f1-3 /proc/loadavg)"
