#!/bin/bash
# Cost of the periodic virial tensor: time per step of kspace_style kifmm with the pressure
# tensor in the thermo output of every step, against the scalar pressure (pressure/scalar yes)
# and no pressure (ratios measured in the same invocation, one thread). Usage: bench/periodic_virial/run.sh LMP [N]
set -euo pipefail
lmp=$(realpath "$1"); n=${2:-10000}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
python3 - "$n" <<'PY'
import random, sys
n = int(sys.argv[1]); random.seed(3)
with open("data.lmp", "w") as f:
    f.write(f"uniform charges\n\n{n} atoms\n1 atom types\n0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n\nMasses\n\n1 1\n\nAtoms # charge\n\n")
    for i in range(n):
        f.write(f"{i + 1} 1 {1 if i % 2 == 0 else -1} {random.random()} {random.random()} {random.random()}\n")
PY
base=""
run() {    # $1: thermo fields, $2: pressure/scalar
  OMP_NUM_THREADS=1 "$lmp" -in "$here/in.virial_cost" -var fields "$1" -var scalar "$2" -log log -screen none -nocite
  grep "Loop time" log | tail -1 | awk '{print $4 / $9}'
}
t0=$(run "elong" no)
t1=$(run "press" yes)
t2=$(run "pxx pyy pzz pxy pxz pyz" no)
echo "N = $n, accuracy 1e-5, thermo every step (5 steps), $(grep 'KIFMM first evaluation' log | head -1 | sed 's/^ *//')"
echo "no pressure:                               $t0 s/step"
echo "scalar pressure (pressure/scalar yes):     $t1 s/step  ($(awk "BEGIN{print $t1/$t0}") x)"
echo "pressure tensor (default):                 $t2 s/step  ($(awk "BEGIN{print $t2/$t0}") x)"
