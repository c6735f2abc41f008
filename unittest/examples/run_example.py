#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Run the quick variant of one example scene in a temporary copy of its directory, then its
outcome checker on the outputs.

usage: run_example.py --lmp LMP --example DIR --checker CHECK.py [--keep]
                      [--skip-if-log REGEX] [-- checker args]

The copy leaves out an existing out/ directory. The input is run as
    LMP -in in.<scene> -var quick 1 -var potentials <repo>/potentials -log out/log.lammps
        -nocite -screen none
(OMP_NUM_THREADS is taken from the environment; ctest sets 1). Then CHECK.py <copy>/out is
run; its exit status is the test's. The copy is removed on success and kept (path printed)
on failure or with --keep. With --skip-if-log, a LAMMPS failure whose log matches REGEX (a
missing feature the scene waits for) exits with status 77, which ctest reports as skipped
(SKIP_RETURN_CODE), printing the matching line.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--example", required=True)
    ap.add_argument("--checker", required=True)
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--skip-if-log", default=None)
    ap.add_argument("checker_args", nargs="*")
    a = ap.parse_args()

    example = os.path.abspath(a.example)
    scene = os.path.basename(example.rstrip("/"))
    repo = os.path.dirname(os.path.dirname(example))
    work = tempfile.mkdtemp(prefix=f"example-{scene}-")
    copy = os.path.join(work, scene)
    shutil.copytree(example, copy, ignore=shutil.ignore_patterns("out", "__pycache__"))
    os.makedirs(os.path.join(copy, "out"), exist_ok=True)
    cmd = [a.lmp, "-in", f"in.{scene}", "-var", "quick", "1",
           "-var", "potentials", os.path.join(repo, "potentials"),
           "-log", "out/log.lammps", "-nocite", "-screen", "none"]
    print("running:", " ".join(cmd), "in", copy, flush=True)
    t0 = time.time()
    run = subprocess.run(cmd, cwd=copy)
    print(f"lammps exit status {run.returncode}, wall time {time.time() - t0:.1f} s", flush=True)
    ok = run.returncode == 0
    if not ok:
        log = os.path.join(copy, "out", "log.lammps")
        text = ""
        if os.path.exists(log):
            with open(log) as f:
                text = f.read()
            print("\n".join(text.splitlines()[-30:]))
        if a.skip_if_log:
            m = re.search(a.skip_if_log, text)
            if m:
                line = text[text.rfind("\n", 0, m.start()) + 1:].split("\n")[0]
                print("SKIPPED: the scene waits for a missing feature:", line)
                shutil.rmtree(work, ignore_errors=True)
                return 77
    else:
        chk = subprocess.run([sys.executable, a.checker, os.path.join(copy, "out")] + a.checker_args)
        ok = chk.returncode == 0
    if ok and not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    else:
        print("outputs kept in", copy)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
