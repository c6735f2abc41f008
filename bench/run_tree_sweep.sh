#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# The automatic tree against a leaf-size sweep (bench_tree_sweep, see bench/bench_tree_sweep.cpp):
# uniform, Plummer and two-cluster points, open and periodic boundaries, on one thread; prints a
# provenance line and markdown tables (keep them together in bench/results/).
#   bench/run_tree_sweep.sh [BUILD_DIR] [extra bench_tree_sweep options]
# BUILD_DIR (default: build/ of this checkout, or $KIFMM_BUILD_DIR) must hold bench/bench_tree_sweep.
# KIFMM_SWEEP_SIZES (default 1e3,1e4,1e5) and KIFMM_SWEEP_ORDERS (default 3-14) set the cases.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-${KIFMM_BUILD_DIR:-$ROOT/build}}
shift || true
sizes=${KIFMM_SWEEP_SIZES:-1e3,1e4,1e5}
orders=${KIFMM_SWEEP_ORDERS:-3,4,5,6,7,8,9,10,11,12,13,14}
echo "commit $(git -C "$ROOT" rev-parse --short HEAD), $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores," \
     "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "command: OMP_NUM_THREADS=1 bench_tree_sweep --sizes $sizes --orders $orders $*"
for boundary in "" --periodic; do
  echo
  OMP_NUM_THREADS=1 "$BUILD/bench/bench_tree_sweep" --sizes "$sizes" --orders "$orders" $boundary "$@"
done
echo
echo "load after $(cut -d' ' -f1-3 /proc/loadavg)"
