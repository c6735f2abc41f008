#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Soak run: runs in.soak with lmp_kifmm and checks its invariants.

    python3 bench/soak/run_soak.py [--steps 100000] [--segments 10] [--lmp build/lmp_kifmm]

A small charged granular system (dipole clumps on fix clump/rigid, free charged spheres,
granular walls, gravity, drag, kspace kifmm with fix kifmm/stride 10) runs STEPS steps in
SEGMENTS runs. After every segment the input prints the thermo line and `info memory`.
Checked (exit status 1 when one fails):
  * no NaN: the per-atom NaN count of positions, velocities and forces is 0, and no thermo
    value is nan or inf;
  * total charge, total |charge|, per-atom mass sum and clump (union) mass sum equal their
    initial values to 1e-12 (relative), atom and clump counts unchanged;
  * memory flat: the malloc'ed pool and the peak RSS at the end exceed the ones after the
    first segment by at most 2 MB (and 5 %).
Prints a table of the invariants and memory at start, after the first segment and at the end.
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(os.path.dirname(here))

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--steps", type=int, default=100000)
ap.add_argument("--segments", type=int, default=10)
ap.add_argument("--lmp", default=os.path.join(root, "build", "lmp_kifmm"))
ap.add_argument("--workdir", default=None, help="where log.soak goes (default: a temporary dir)")
ap.add_argument("--var", action="append", default=[], metavar="NAME=VALUE",
                help="extra input variable (e.g. NC=150)")
args = ap.parse_args()
if args.steps % args.segments:
    sys.exit("steps must be a multiple of segments")

work = args.workdir or tempfile.mkdtemp(prefix="kifmm-soak-")
os.makedirs(work, exist_ok=True)
log = os.path.join(work, "log.soak")
cmd = [args.lmp, "-in", os.path.join(here, "in.soak"), "-log", log, "-screen", "none",
       "-var", "steps", str(args.steps), "-var", "segments", str(args.segments),
       "-var", "potentials", os.path.join(root, "potentials")]
for v in args.var:
    name, value = v.split("=", 1)
    cmd += ["-var", name, value]
env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))
print("command:", " ".join(cmd), flush=True)
t0 = time.time()
c0 = os.times()
proc = subprocess.run(cmd, cwd=work, env=env)
wall = time.time() - t0
c1 = os.times()
cpu = (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)
if proc.returncode != 0:
    print(open(log).read()[-3000:] if os.path.exists(log) else "(no log)")
    sys.exit(f"lmp_kifmm failed with exit status {proc.returncode}")

text = open(log).read()
# thermo lines after the header "Step Atoms f_clumps[1] ..."
cols = None
rows = {}
for line in text.splitlines():
    if line.startswith("Step Atoms"):
        cols = line.split()
        continue
    if cols:
        f = line.split()
        if len(f) == len(cols) and re.fullmatch(r"\d+", f[0]):
            rows[int(f[0])] = dict(zip(cols, f))
mem = []    # (label, dynamic, pool, maxrss) in Mbyte
label = None
for line in text.splitlines():
    m = re.match(r"SOAK (start|segment \d+|done)", line)
    if m:
        label = m.group(1)
    m = re.match(r"Total dynamically allocated memory: ([\d.eE+-]+) Mbyte", line)
    if m:
        dyn = float(m.group(1))
    m = re.match(r"Current reserved memory pool size: ([\d.eE+-]+) Mbyte", line)
    if m:
        pool = float(m.group(1))
    m = re.match(r"Maximum resident set size: ([\d.eE+-]+) Mbyte", line)
    if m:
        mem.append((label, dyn, pool, float(m.group(1))))

failures = []
steps = sorted(rows)
if not steps or steps[-1] != args.steps:
    failures.append(f"thermo output ends at step {steps[-1] if steps else None}, not {args.steps}")
first = rows[steps[0]]
keys = ["Atoms", "f_clumps[1]", "v_qtot", "c_qabs", "v_mtot", "c_cmass"]
for s in steps:
    r = rows[s]
    for k, v in r.items():
        if not math.isfinite(float(v)):
            failures.append(f"step {s}: {k} = {v}")
    if float(r["c_nnan"]) != 0:
        failures.append(f"step {s}: {r['c_nnan']} NaN per-atom values")
    for k in keys:
        a, b = float(first[k]), float(r[k])
        if abs(a - b) > 1e-12 * max(abs(a), 1e-300):
            failures.append(f"step {s}: {k} = {r[k]} differs from its initial {first[k]}")
if len(mem) < 3:
    failures.append("fewer than 3 `info memory` outputs in the log")
else:
    ref, end = mem[1], mem[-1]
    for idx, name in ((2, "malloc'ed pool"), (3, "peak RSS")):
        grow = end[idx] - ref[idx]
        if grow > 2.0 and grow > 0.05 * ref[idx]:
            failures.append(f"{name} grew from {ref[idx]} MB (after segment 1) to {end[idx]} MB")

print(f"log: {log}")
print(f"wall {wall:.1f} s, CPU {cpu:.1f} s, load average {os.getloadavg()[0]:.2f} at the end")
print("step       atoms clumps  total q       sum|q|   mass(atoms)          mass(clumps)        NaN  elong")
for s in steps:
    r = rows[s]
    print(f"{s:<10d} {r['Atoms']:>5} {float(r['f_clumps[1]']):6.0f}  {r['v_qtot']:<12} {r['c_qabs']:<6} "
          f"{r['v_mtot']:<20} {r['c_cmass']:<19} {float(r['c_nnan']):3.0f}  {float(r['E_long']):.6g}")
print("memory (MB)        LAMMPS-allocated  malloc'ed pool  peak RSS")
for lab, dyn, pool, rss in mem:
    print(f"{lab:<18} {dyn:16.2f} {pool:15.2f} {rss:9.2f}")
if failures:
    print("FAILED:")
    for f in failures[:20]:
        print("  " + f)
    sys.exit(1)
print(f"PASS: {args.steps} steps, no NaN, charge/mass/counts unchanged, memory flat "
      f"(peak RSS {mem[0][3]:.2f} MB at start, {mem[1][3]:.2f} MB after segment 1, "
      f"{mem[-1][3]:.2f} MB at the end)")
