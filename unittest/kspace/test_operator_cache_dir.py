#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""The on-disk operator cache across processes: KIFMM_CACHE_DIR names a directory that does not
exist. The first lmp_kifmm run creates it, computes the operators and writes them there; the
second run (a new process, so an empty in-memory cache) reads them back.

usage: test_operator_cache_dir.py --lmp LMP

Disk hit: the operator file of run 1 is neither removed nor rewritten by run 2 (a computed
set is always written to a temporary name and renamed over the file, which changes its inode;
its modification time is set back to 2000-01-01 after run 1 and must stay), and run 2's
precompute time is below run 1's (reading takes about a third of computing at order 10).
"""
import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

INPUT = """units lj
atom_style charge
boundary f f f
region box block 0 10 0 10 0 10 units box
create_box 1 box
create_atoms 1 random 4000 4711 box
mass 1 1.0
variable q atom 2*(id%2)-1
set group all charge v_q
pair_style zero 1.0
pair_coeff * *
kspace_style kifmm 1e-5
kspace_modify kifmm order 10 leaf 64
run 0 post no
"""


def run(lmp, work, cache, n):
    log = os.path.join(work, f"log.{n}")
    env = dict(os.environ, KIFMM_CACHE_DIR=cache)
    p = subprocess.run([lmp, "-in", "in.cache", "-log", log, "-screen", "none", "-nocite"],
                       cwd=work, env=env)
    text = open(log).read() if os.path.exists(log) else ""
    if p.returncode != 0:
        print("\n".join(text.splitlines()[-20:]))
        sys.exit(f"run {n}: lmp_kifmm exit status {p.returncode}")
    return text


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="kifmm-cache-dir-")
    cache = os.path.join(work, "not", "yet", "lammps-kifmm")
    with open(os.path.join(work, "in.cache"), "w") as f:
        f.write(INPUT)
    failures = []

    def check(ok, what):
        print(("ok:   " if ok else "FAIL: ") + what)
        if not ok:
            failures.append(what)

    precompute = []
    files = []
    for n in (1, 2):
        log = run(a.lmp, work, cache, n)
        check(f"operator cache = {cache}\n" in log, f"run {n}: the log names the cache directory")
        check("WARNING: kspace_style kifmm: cannot create" not in log, f"run {n}: no cache warning")
        m = re.search(r"precompute ([0-9.eE+-]+) s, operators ([0-9.eE+-]+) MB", log)
        check(m is not None and float(m.group(2)) > 0, f"run {n}: operators in use")
        precompute.append(float(m.group(1)) if m else float("nan"))
        now = sorted(glob.glob(os.path.join(cache, "kifmm_ops_*.bin")))
        if n == 1:
            check(os.path.isdir(cache), "run 1 created the directory")
            check(len(now) >= 1, f"run 1 wrote operator files: {now}")
            files = [(p, os.stat(p).st_ino) for p in now]
            for p in now:
                os.utime(p, (946684800, 946684800))    # 2000-01-01
        else:
            check(now == [p for p, _ in files], f"run 2 added or removed no file: {now}")
            for p, ino in files:
                st = os.stat(p) if os.path.exists(p) else None
                check(st is not None and st.st_ino == ino and int(st.st_mtime) == 946684800,
                      f"run 2 read {os.path.basename(p)} without rewriting it")
    print(f"precompute: run 1 {precompute[0]:.3g} s (computed), run 2 {precompute[1]:.3g} s (read)")
    check(precompute[1] < precompute[0], "run 2 precomputes faster than run 1")
    if failures:
        print("outputs kept in", work)
        return 1
    shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
