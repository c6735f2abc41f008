#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# README command (a): install what is missing, build, run the default example (charges-box,
# quick variant) with lmp_kifmm, plot its energy, and say where the outputs are.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${KIFMM_BUILD_DIR:-$root/build}"
bash "$root/tools/build.sh"
example="${1:-charges-box}"
quick="${KIFMM_EXAMPLE_QUICK:-1}"
cd "$root/examples/$example"
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
mkdir -p out
"$build/lmp_kifmm" -in "in.$example" -var quick "$quick" -log out/log.lammps -nocite
/usr/bin/python3 plot_energy.py out >/dev/null
echo
echo "Example $example finished. Outputs in $root/examples/$example/out/:"
ls -1 "$root/examples/$example/out" | sed 's/^/  /'

