#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Mutation checks of the locally essential tree's conditions (doc/design.md, "MPI"): each
# mutation of src/KIFMM/engine/distributed.cpp must make some engine distributed test fail.
#   git worktree add ../kifmm-mutate HEAD && WT=../kifmm-mutate bash tools/mutate_let.sh
# Rebuilds engine_test_distributed in $WT/build once per mutation (about 2 min each on 2 cores)
# and prints the tests that fail on 2, 3 and 4 ranks ("none": the mutation was not caught).
set -u
WT="$(cd "${WT:?set WT to a worktree of this repository}" && pwd)"
cd "$WT/src/KIFMM/engine"
good="$(mktemp)"
cp distributed.cpp "$good"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
[ -d $WT/build ] || nice cmake -S $WT -B $WT/build -DCMAKE_BUILD_TYPE=Release -DKIFMM_ENGINE_ONLY=ON >/dev/null
mut() { name=$1; shift; cp "$good" distributed.cpp; python3 -c "
import sys
s=open('distributed.cpp').read()
for a,b in zip(sys.argv[1::2],sys.argv[2::2]):
    assert a in s, a; s=s.replace(a,b)
open('distributed.cpp','w').write(s)" "$@" || { echo "$name: pattern missing"; return; }
  nice make -C $WT/build engine_test_distributed 2>&1 | grep " error"
  res=""
  for np in 2 3 4; do
    out=$(nice mpiexec --oversubscribe --bind-to none -np $np $WT/build/unittest/engine/engine_test_distributed 2>&1)
    f=$(echo "$out" | grep -a "FAILED  \]" | grep -ao "Distributed\.[A-Za-z]*" | sort -u | tr '\n' ' ')
    res="$res np$np: ${f:-none};"
  done
  echo "$name -> $res"
}
mut M1_children_no_coarse_leaf "(y.leaf || y.coarse ? y.cell.level <= p.level : y.cell.level == p.level)" "(y.cell.level == p.level)"
mut M2_points_no_X "(y.leaf || y.coarse || y.cell.level >= d.level) && touch(d" "(y.leaf || y.coarse) && touch(d"
mut M3_no_w_direct "if (a.gsrc == 0 || (int) a.gsrc > nsurf) return false;" "return false;"
mut M4_points_no_U "(y.leaf || y.coarse || y.cell.level >= d.level) && touch(d" "(y.coarse || y.cell.level >= d.level) && touch(d"
mut S1_own_points_sent_back "if (tree.trg_order[i] < skip_begin || tree.trg_order[i] >= skip_end) pts.push_back" "pts.push_back"
mut S2_no_asking_cells_in_F "if (from_e > from_b) {" "if (false) {"
mut S3_coarse_w_as_leaf "(y.coarse || !touch(a, y.cell, shifts))" "(!touch(a, y.cell, shifts))"
mut S4_coarse_not_sent "            q.insert(q.end(), {C.level, C.ix, C.iy, C.iz, 2});
            ++q[at];" "            (void) at;"
cp "$good" distributed.cpp
echo done
