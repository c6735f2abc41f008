#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Cost of induced dipoles (fix kifmm/polarize) per step, in field evaluations and time,
against plain charges at the same accuracy.

Atoms: spheres of diameter 1 on a jittered simple cubic lattice of spacing 1.25 (jitter 0.15),
every other one charged +-1 (neutral), the others polarizable and neutral (Clausius-Mossotti,
permittivity 10: alpha = 0.094), in a uniform field 0.5 along z (fix efield); open boundaries
or a periodic cube. A short run (fix nve/sphere, small random velocities, no pair forces)
starts each solve from the last step's dipoles. Reported per accuracy of kspace kifmm (the
solve's tolerance a tenth of it): the mean iterations and field evaluations per solve after the
first step (a step adds the field of the charges at the polarizable atoms and the force
evaluation with the dipoles), the time per step (LAMMPS's Loop time / STEPS) with the
polarizable atoms and with plain charges (the same atoms all charged +-1, no dipoles), their
ratio, and the relative RMS difference of the induced dipoles from a tight solve (accuracy
1e-10, tolerance 1e-12) at the first step.

usage: run.py --lmp LMP [--sizes 1e4] [--steps 10] [--cases open,periodic]
              [--accuracies 1e-3,1e-5] [--out FILE.md]
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

SPACING, JITTER = 1.25, 0.15


def write_data(path, n, periodic, seed=1):
    k = max(2, round(n ** (1 / 3)))
    rnd = random.Random(seed)
    side = k * SPACING
    lo, hi = (0.0, side) if periodic else (-1.0, side + 1.0)
    with open(path, "w") as f:
        f.write(f"polarizable spheres\n\n{k ** 3} atoms\n2 atom types\n\n")
        for ax in "xyz":
            f.write(f"{lo} {hi} {ax}lo {ax}hi\n")
        f.write("\nAtoms # hybrid\n\n")
        i = 0
        for a in range(k):
            for b in range(k):
                for c in range(k):
                    i += 1
                    x = [(v + 0.5) * SPACING + rnd.uniform(-JITTER, JITTER) for v in (a, b, c)]
                    charged = (a + b + c) % 2 == 0
                    q = (1 if (a + b) % 2 == 0 else -1) if charged else 0
                    f.write(f"{i} {1 if charged else 2} {x[0]:.15g} {x[1]:.15g} {x[2]:.15g} 1 1 {q} 0 0 0\n")
    return k ** 3


def run(lmp, work, periodic, acc, tol, steps, polarize):
    lines = ["units lj", "atom_style hybrid sphere dipole", f"boundary {'p p p' if periodic else 'f f f'}",
             "atom_modify map array", "read_data data.lmp", f"neighbor {0.5 * SPACING:.6g} bin",
             "neigh_modify delay 0 every 1000 check no one 100000 page 1000000",
             "pair_style zero 1.0", "pair_coeff * *", "velocity all create 0.05 4711 loop geom"]
    if polarize:
        lines += ["group pol type 2", "fix ef all efield 0.0 0.0 0.5",
                  f"fix pol pol kifmm/polarize permittivity 10 tol {tol}"]
    else:    # plain charges: every atom charged +-1 (the polarizable ones too), no dipoles
        lines += ["group other type 2", "variable qq atom 1-2*((floor(x/1.25)+floor(y/1.25))%2)",
                  "set group other charge v_qq"]
    lines += [f"kspace_style kifmm {acc}", "fix nve all nve/sphere", "timestep 0.005"]
    if polarize:
        lines += ["variable it equal f_pol[1]", "variable ev equal f_pol[3]",
                  f"fix av all ave/time 1 {steps} {steps} v_it v_ev"]
        lines += ["thermo_style custom step pe f_pol[1] f_pol[3]"]
    lines += ["run 0 post no"]
    if polarize:
        lines += ["write_dump pol custom dipoles.dump id mux muy muz modify sort id format float %.16g"]
    lines += [f"run {steps} post no"]
    if polarize:
        lines += ['print "MEAN $(f_av[1]) $(f_av[2])"']
    with open(os.path.join(work, "in.lmp"), "w") as f:
        f.write("\n".join(lines) + "\n")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.run([lmp, "-in", "in.lmp", "-log", "log.lammps", "-screen", "none", "-nocite"], cwd=work, env=env)
    text = open(os.path.join(work, "log.lammps")).read() if os.path.exists(os.path.join(work, "log.lammps")) else ""
    if p.returncode != 0:
        err = [l for l in text.splitlines() if "ERROR" in l]
        sys.stderr.write(f"{acc}: failed: {err[-1] if err else 'no ERROR line'}\n")
        return None
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps", text)
    out = {"t": float(loops[-1][0]) / max(1, int(loops[-1][1]))}
    m = re.search(r"^MEAN (\S+) (\S+)$", text, re.M)
    if m:
        out["iterations"], out["evaluations"] = float(m.group(1)), float(m.group(2))
        rows = {}
        with open(os.path.join(work, "dipoles.dump")) as f:
            dl = f.read().splitlines()
        k = next(i for i, l in enumerate(dl) if l.startswith("ITEM: ATOMS"))
        for l in dl[k + 1:]:
            v = l.split()
            if v:
                rows[int(v[0])] = [float(x) for x in v[1:4]]
        out["dipoles"] = rows
    return out


def rel(a, b):
    num = sum((a[i][c] - b[i][c]) ** 2 for i in b for c in range(3))
    den = sum(b[i][c] ** 2 for i in b for c in range(3))
    return math.sqrt(num / den)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--sizes", default="1e4")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--cases", default="open,periodic")
    ap.add_argument("--accuracies", default="1e-3,1e-5")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    a.lmp = os.path.abspath(a.lmp)
    out = open(a.out, "w") if a.out else sys.stdout
    out.write("| boundary | N | accuracy | tol | iterations per solve | field evaluations per solve | "
              "s / step polarizable | s / step plain charges | ratio | dipoles' error |\n")
    out.write("|---|---|---|---|---|---|---|---|---|---|\n")
    for case in a.cases.split(","):
        periodic = case == "periodic"
        for ns in a.sizes.split(","):
            work = tempfile.mkdtemp(prefix=f"polarize-{case}-")
            n = write_data(os.path.join(work, "data.lmp"), int(float(ns)), periodic)
            ref = run(a.lmp, work, periodic, "1e-10", "1e-12", 1, True)
            for acc in a.accuracies.split(","):
                tol = f"{float(acc) / 10:g}"
                p = run(a.lmp, work, periodic, acc, tol, a.steps, True)
                q = run(a.lmp, work, periodic, acc, tol, a.steps, False)
                if not p or not q or not ref:
                    out.write(f"| {case} | {n} | {acc} | {tol} | failed | | | | | |\n")
                    continue
                err = rel(p["dipoles"], ref["dipoles"])
                out.write(f"| {'p p p' if periodic else 'f f f'} | {n} | {acc} | {tol} | {p['iterations']:.2f} | "
                          f"{p['evaluations']:.2f} | {p['t']:.4g} | {q['t']:.4g} | {p['t'] / q['t']:.2f} | {err:.2e} |\n")
                out.flush()
            shutil.rmtree(work)
    return 0


if __name__ == "__main__":
    sys.exit(main())
