#!/bin/bash
# Cost of the periodic virial tensor: time per step of kspace_style kifmm with the pressure
# tensor in the thermo output of every step, against the scalar pressure (pressure/scalar yes)
# and no pressure; with fix nvt and with fix npt aniso (a box that changes shape at every step);
# p p p and a slab (p p f) (ratios measured in the same invocation, one thread). Usage: bench/periodic_virial/run.sh LMP [N]
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
run() {    # $1: thermo fields, $2: pressure/scalar, $3: boundary in z, $4: integrator (none, nvt, npt)
  OMP_NUM_THREADS=1 "$lmp" -in "$here/in.virial_cost" -var fields "$1" -var scalar "$2" -var zbnd "${3:-p}" \
    -var integrator "${4:-none}" -log log -screen none -nocite
  grep "Loop time" log | tail -1 | awk '{print $4 / $9}'
}
ratio() { awk "BEGIN{print $1/$2}"; }
t0=$(run "elong" no)
t1=$(run "press" yes)
t2=$(run "pxx pyy pzz pxy pxz pyz" no)
first=$(grep 'KIFMM first evaluation' log | head -1 | sed 's/^ *//')
t3=$(run "pxx pyy pzz pxy pxz pyz" no p nvt)
t4=$(run "pxx pyy pzz pxy pxz pyz" no p npt)
s0=$(run "elong" no f)
s2=$(run "pxx pyy pzz pxy pxz pyz" no f)
s3=$(run "pxx pyy pzz pxy pxz pyz" no f nvt)
s4=$(run "pxx pyy pzz pxy pxz pyz" no f npt)
echo "N = $n, accuracy 1e-5, thermo every step (5 steps), $first"
echo "no pressure:                               $t0 s/step"
echo "scalar pressure (pressure/scalar yes):     $t1 s/step  ($(ratio $t1 $t0) x)"
echo "pressure tensor (default):                 $t2 s/step  ($(ratio $t2 $t0) x)"
echo "pressure tensor, fix nvt:                  $t3 s/step  ($(ratio $t3 $t0) x)"
echo "pressure tensor, fix npt aniso:            $t4 s/step  ($(ratio $t4 $t0) x; the box changes shape at every step, the grid's tables are made again)"
echo "slab (p p f), no pressure:                 $s0 s/step"
echo "slab, pressure tensor:                     $s2 s/step  ($(ratio $s2 $s0) x)"
echo "slab, pressure tensor, fix nvt:            $s3 s/step  ($(ratio $s3 $s0) x)"
echo "slab, pressure tensor, fix npt on x and y: $s4 s/step  ($(ratio $s4 $s0) x)"
