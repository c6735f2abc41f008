#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Speed against error of kspace_style kifmm with point dipoles: against the direct sum with
open boundaries (pair lj/cut/dipole/cut, epsilon 0, cutoff beyond the box) and against
LAMMPS's ewald/disp + pair lj/long/dipole/long in a periodic cube; and the cost of dipoles
against plain charges (the same atoms with their moments set to zero) at the same accuracy.

Atoms: spheres of diameter 1 on a jittered simple cubic lattice of spacing 1.25 (jitter 0.15,
no overlaps), charges +-1 (neutral), dipole moments of length 0.8 in random directions
(atom_style hybrid sphere dipole). References: open, the direct sum itself; periodic,
kifmm at accuracy 1e-10 (tested against an Ewald sum of charges and dipoles:
unittest/engine/test_dipoles.cpp). Reported per solver: relative RMS errors of forces and
torques, time per step (LAMMPS's Loop time / STEPS: pair + kspace + neighbor lists; no time
integration), and for kifmm the ratio of its time to the other solver's at the same error
(log-log interpolation between that solver's settings; '-' outside their range) and to plain
charges at the same accuracy.

usage: run.py --lmp LMP [--sizes 1e4] [--steps 5] [--cases open,periodic] [--out FILE.md]
"""
import argparse
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from matched_error import time_at  # noqa: E402

SPACING, JITTER, MU = 1.25, 0.15, 0.8
KIFMM = ["1e-3", "1e-5", "1e-7"]
EWALD_DISP = [("1e-3", 3), ("1e-4", 3), ("1e-5", 4), ("1e-6", 4)]    # accuracy, real-space cutoff in spacings


def write_data(path, n, periodic, dipoles=True, seed=1):
    k = max(2, round(n ** (1 / 3)))
    rnd = random.Random(seed)
    side = k * SPACING
    lo, hi = (0.0, side) if periodic else (-1.0, side + 1.0)
    with open(path, "w") as f:
        f.write(f"dipole spheres\n\n{k ** 3} atoms\n1 atom types\n\n")
        for ax in "xyz":
            f.write(f"{lo} {hi} {ax}lo {ax}hi\n")
        f.write("\nAtoms # hybrid\n\n")
        i = 0
        for a in range(k):
            for b in range(k):
                for c in range(k):
                    i += 1
                    x = [(v + 0.5) * SPACING + rnd.uniform(-JITTER, JITTER) for v in (a, b, c)]
                    z = rnd.uniform(-1, 1)
                    ph = rnd.uniform(0, 2 * math.pi)
                    s = math.sqrt(1 - z * z)
                    m = [MU * s * math.cos(ph), MU * s * math.sin(ph), MU * z] if dipoles else [0, 0, 0]
                    q = 1 if (a + b + c) % 2 == 0 else -1
                    f.write(f"{i} 1 {x[0]:.15g} {x[1]:.15g} {x[2]:.15g} 1 1 {q} {m[0]:.15g} {m[1]:.15g} {m[2]:.15g}\n")
    return k ** 3, side


def run(lmp, work, periodic, solver, acc, steps, side, cut=3.0):
    lines = ["units lj", "atom_style hybrid sphere dipole", f"boundary {'p p p' if periodic else 'f f f'}",
             "atom_modify map array", "read_data data.lmp", f"neighbor {0.5 * SPACING:.6g} bin",
             "neigh_modify delay 0 every 1000 check no one 100000 page 1000000"]
    if solver == "kifmm":
        lines += ["pair_style zero 1.0", "pair_coeff * *", f"kspace_style kifmm {acc}"]
    elif solver == "direct":
        lines += [f"pair_style lj/cut/dipole/cut 1.0 {2 * side:.6g}", "pair_coeff * * 0.0 1.0"]
    else:    # ewald/disp: its accuracy is relative to the force between two unit charges at unit distance
        lines += [f"pair_style lj/long/dipole/long cut long {cut * SPACING:.6g}", "pair_coeff * * 0.0 1.0",
                  f"kspace_style ewald/disp {acc}"]
    lines += ["thermo_style custom step pe", "run 0 post no",    # setup (order search, tables)
              "write_dump all custom forces.dump id fx fy fz tqx tqy tqz modify sort id format float %.16g",
              f"run {steps} post no"]
    with open(os.path.join(work, "in.lmp"), "w") as f:
        f.write("\n".join(lines) + "\n")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.run([lmp, "-in", "in.lmp", "-log", "log.lammps", "-screen", "none", "-nocite"], cwd=work, env=env)
    text = open(os.path.join(work, "log.lammps")).read() if os.path.exists(os.path.join(work, "log.lammps")) else ""
    if p.returncode != 0:
        err = [l for l in text.splitlines() if "ERROR" in l]
        sys.stderr.write(f"{solver} {acc}: failed: {err[-1] if err else 'no ERROR line'}\n")
        return None, None
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", text)
    t = float(loops[-1][0]) / max(1, int(loops[-1][1]))
    rows = {}
    with open(os.path.join(work, "forces.dump")) as f:
        lines = f.read().splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    for l in lines[k + 1:]:
        v = l.split()
        if v:
            rows[int(v[0])] = [float(x) for x in v[1:7]]
    return t, rows


def rel_error(f, ref, cols):
    num = sum((f[i][c] - ref[i][c]) ** 2 for i in ref for c in cols)
    den = sum(ref[i][c] ** 2 for i in ref for c in cols)
    return math.sqrt(num / den)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--sizes", default="1e4")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--cases", default="open,periodic")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    out = open(a.out, "w") if a.out else sys.stdout
    out.write("| boundary | N | solver | accuracy | force error | torque error | s / step | "
              "kifmm / other at that error | dipoles / charges at that accuracy |\n")
    out.write("|---|---|---|---|---|---|---|---|---|\n")
    for case in a.cases.split(","):
        periodic = case == "periodic"
        for ns in a.sizes.split(","):
            work = tempfile.mkdtemp(prefix=f"dipoles-{case}-")
            qwork = tempfile.mkdtemp(prefix=f"charges-{case}-")
            n, side = write_data(os.path.join(work, "data.lmp"), int(float(ns)), periodic)
            write_data(os.path.join(qwork, "data.lmp"), int(float(ns)), periodic, dipoles=False)
            rows, other = [], []
            if periodic:
                _, ref = run(a.lmp, work, True, "kifmm", "1e-10", 1, side)
                for acc, cs in EWALD_DISP:
                    t, f = run(a.lmp, work, True, "ewald/disp", acc, a.steps, side, cs)
                    e = rel_error(f, ref, range(3)) if f else None
                    et = rel_error(f, ref, range(3, 6)) if f else None
                    other.append((max(e, et) if f else None, t))
                    rows.append(("ewald/disp", f"{acc} (cutoff {cs} spacings)", e, et, t, "", ""))
            else:
                t, ref = run(a.lmp, work, False, "direct", "", max(1, a.steps // 2), side)
                rows.append(("direct (lj/cut/dipole/cut)", "exact", 0.0, 0.0, t, "", ""))
                other = [(1e-16, t), (1.0, t)]    # the direct sum's time at any error
            for acc in KIFMM:
                t, f = run(a.lmp, work, periodic, "kifmm", acc, a.steps, side)
                tq, _ = run(a.lmp, qwork, periodic, "kifmm", acc, a.steps, side)
                e = rel_error(f, ref, range(3)) if f else None
                et = rel_error(f, ref, range(3, 6)) if f else None
                to = time_at(max(e, et), other) if f else None
                rows.append(("kifmm", acc, e, et, t, f"{t / to:.3g}" if to and t else "-",
                             f"{t / tq:.2f}" if t and tq else "-"))
            for s, acc, e, et, t, r, rq in rows:
                fe = "failed" if e is None else f"{e:.2e}"
                te = "failed" if et is None else f"{et:.2e}"
                ts = f"{t:.4g}" if t is not None else "-"
                out.write(f"| {'p p p' if periodic else 'f f f'} | {n} | {s} | {acc} | {fe} | {te} | {ts} | {r} | {rq} |\n")
            out.flush()
            shutil.rmtree(work)
            shutil.rmtree(qwork)
    return 0


if __name__ == "__main__":
    sys.exit(main())
