#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# bench_smoke: run the solver benchmark driver on its tiny profile into a fresh directory,
# then check the report. Usage: smoke.sh BENCH_SOLVERS_BINARY OUTDIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="$1" out="$2"
rm -rf "$out"
OMP_NUM_THREADS=1 bash "$root/bench/solvers/run.sh" --tiny --bin "$bin" --out "$out"
py=python3
[ -x /usr/bin/python3 ] && py=/usr/bin/python3
"$py" "$here/check_smoke.py" "$out"
