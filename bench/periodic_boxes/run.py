#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Speed against error of kspace_style kifmm and LAMMPS's pppm in periodic boxes that are not
cubes: p p p in rectangular boxes and slabs (p p f; pppm with kspace_modify slab 3, LAMMPS's
recommended factor, whose own approximation error, about 3e-5 here, bounds what pppm can reach
in a slab), uniform charges and a sediment layer on the floor (in a slab and in a periodic cube).

For each case (box, boundary, N, distribution) a data file of N charges +-1 (neutral) is
written, the reference forces are kifmm's at accuracy 1e-10 (tested against ewald in these
geometries: unittest/periodic), then every solver runs STEPS steps of the same configuration
(no time integration) with lmp_kifmm. pppm is tuned: every requested accuracy with every pair
cutoff of PPPM_CUTOFFS, and its time at an error is that of the fastest settings around it (the
settings no other setting beats in both error and time). Reported per solver: the relative RMS
force error against the reference and the time per step (LAMMPS's Loop time / STEPS: pair +
kspace + neighbor lists), and per kifmm setting the ratio of its time to tuned pppm's at the
same error (log-log interpolation between the fastest pppm settings around that error; '>= r'
when kifmm's error is above all of them: the least accurate of them meets it; '-' when pppm
does not reach kifmm's error).

usage: run.py --lmp LMP [--sizes 1e4,1e5] [--steps 10] [--out FILE.md] [--cases NAME,...]
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
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from matched_error import frontier, time_at  # noqa: E402

CASES = {
    # name: (lx, ly, lz, boundary, distribution)
    "box_2x1x1": (2.0, 1.0, 1.0, "p p p", "uniform"),
    "box_4x1x1": (4.0, 1.0, 1.0, "p p p", "uniform"),
    "slab_uniform": (1.0, 1.0, 0.5, "p p f", "uniform"),
    "slab_sediment": (1.0, 1.0, 0.5, "p p f", "sediment"),
    "box_sediment": (1.0, 1.0, 1.0, "p p p", "sediment"),
}
KIFMM = ["1e-3", "1e-5", "1e-7"]
# pppm: every accuracy with every pair cutoff (in mean atom spacings)
PPPM_ACCURACIES = ["1e-3", "1e-4", "1e-5", "1e-6"]
PPPM_CUTOFFS = [2, 3, 4, 6]


def write_data(path, n, case, seed=1):
    lx, ly, lz, _, dist = CASES[case]
    rnd = random.Random(seed)
    with open(path, "w") as f:
        f.write(f"{case}\n\n{n} atoms\n1 atom types\n\n0 {lx} xlo xhi\n0 {ly} ylo yhi\n0 {lz} zlo zhi\n\n")
        f.write("Masses\n\n1 1\n\nAtoms # charge\n\n")
        for i in range(n):
            z = rnd.uniform(0, lz) if dist == "uniform" else lz * 0.1 * rnd.random() ** 2    # dense at the floor
            f.write(f"{i + 1} 1 {1 if i % 2 == 0 else -1} {rnd.uniform(0, lx):.15g} {rnd.uniform(0, ly):.15g} {z:.15g}\n")


def spacing(n, case):
    lx, ly, lz, _, _ = CASES[case]
    return (lx * ly * lz / n) ** (1 / 3)


def run(lmp, work, case, n, solver, acc, steps, cut_spacings=3, f_rms=1.0):
    lx, ly, lz, boundary, _ = CASES[case]
    lines = ["units lj", "atom_style charge", f"boundary {boundary}", "atom_modify map array",
             "read_data data.lmp", f"neighbor {0.5 * spacing(n, case):.6g} bin", "neigh_modify delay 0 every 1000 check no one 10000"]
    if solver == "kifmm":
        lines += ["pair_style zero 0.01", "pair_coeff * *", f"kspace_style kifmm {acc}"]
    else:
        cut = cut_spacings * spacing(n, case)
        # LAMMPS's accuracy is relative to the force between two unit charges at unit distance
        # (1 in lj units): the requested relative error times the RMS force, as bench/solvers
        lines += [f"pair_style coul/long {cut:.6g}", "pair_coeff * *", "pair_modify table 0",
                  f"kspace_style pppm {float(acc) * f_rms:.6g}"]
        if boundary == "p p f":
            lines += ["kspace_modify slab 3.0"]
    lines += ["thermo_style custom step elong", "run 0 post no",    # setup (order search, tables)
              f"write_dump all custom forces.dump id fx fy fz modify sort id format float %.16g",
              f"run {steps} post no"]
    with open(os.path.join(work, "in.lmp"), "w") as f:
        f.write("\n".join(lines) + "\n")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.run([lmp, "-in", "in.lmp", "-log", "log.lammps", "-screen", "none", "-nocite"], cwd=work, env=env)
    if p.returncode != 0:
        log = os.path.join(work, "log.lammps")
        err = [l for l in open(log).read().splitlines() if "ERROR" in l] if os.path.exists(log) else []
        sys.stderr.write(f"{case} N={n} {solver} {acc}: failed: {err[-1] if err else 'no ERROR line'}\n")
        return None, None
    text = open(os.path.join(work, "log.lammps")).read()
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", text)
    t = float(loops[-1][0]) / max(1, int(loops[-1][1]))
    forces = {}
    with open(os.path.join(work, "forces.dump")) as f:
        lines = f.read().splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    for l in lines[k + 1:]:
        p_ = l.split()
        if p_:
            forces[int(p_[0])] = [float(v) for v in p_[1:4]]
    return t, forces


def rel_error(f, ref):
    num = sum((a - b) ** 2 for i in ref for a, b in zip(f[i], ref[i]))
    den = sum(a * a for i in ref for a in ref[i])
    return math.sqrt(num / den)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--sizes", default="1e4,1e5")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    a.lmp = os.path.abspath(a.lmp) if os.path.sep in a.lmp else a.lmp    # the runs change directory
    out = open(a.out, "w") if a.out else sys.stdout
    out.write("| case | box | boundary | N | solver | accuracy | force error | s / step | kifmm / tuned pppm at that error |\n")
    out.write("|---|---|---|---|---|---|---|---|---|\n")
    for case in a.cases.split(","):
        for ns in a.sizes.split(","):
            n = int(float(ns))
            work = tempfile.mkdtemp(prefix=f"pbox-{case}-")
            write_data(os.path.join(work, "data.lmp"), n, case)
            _, ref = run(a.lmp, work, case, n, "kifmm", "1e-10", 1)
            f_rms = math.sqrt(sum(v * v for i in ref for v in ref[i]) / len(ref))
            rows, pppm = [], []
            for acc in PPPM_ACCURACIES:
                for cs in PPPM_CUTOFFS:
                    t, f = run(a.lmp, work, case, n, "pppm", acc, a.steps, cs, f_rms)
                    e = rel_error(f, ref) if f else None
                    pppm.append((e, t))
                    rows.append(("pppm", f"{acc} (cutoff {cs} spacings)", e, t, ""))
            fastest = frontier(pppm)
            rows = [r if (r[2], r[3]) not in fastest else r[:4] + ("fastest",) for r in rows]
            for acc in KIFMM:
                t, f = run(a.lmp, work, case, n, "kifmm", acc, a.steps)
                e = rel_error(f, ref) if f else None
                tp = time_at(e, fastest) if e else None
                ratio = f"{t / tp:.2f}" if tp and t else "-"
                if e and t and tp is None and fastest and e > fastest[-1][0]:
                    # a larger error than pppm's least accurate fastest setting: that setting meets
                    # it, so pppm needs at most its time there
                    ratio = f">= {t / fastest[-1][1]:.2f}"
                rows.append(("kifmm", acc, e, t, ratio))
            lx, ly, lz, bnd, _ = CASES[case]
            for s, acc, e, t, r in rows:
                es = f"{e:.2e}" if e is not None else "failed"
                ts = f"{t:.4g}" if t is not None else "-"
                out.write(f"| {case} | {lx:g} x {ly:g} x {lz:g} | {bnd} | {n} | {s} | {acc} | {es} | {ts} | {r} |\n")
            out.flush()
            shutil.rmtree(work)
    return 0


if __name__ == "__main__":
    sys.exit(main())
