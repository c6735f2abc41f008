#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Snapshots of the example scenes (start and end states) for the solver benchmark.

Each scene of examples/ is copied into WORK/scenes/NAME/ (the examples themselves are not
touched), two `write_dump ... custom` lines are added to the copy of its input (after the
`run 0` that starts the production run, and at the end), and the copy is run with lmp_kifmm
(quick variant by default). Each dump is converted into an atom_style charge data file
WORK/scenes/NAME_start.data / NAME_end.data with a JSON file of metadata (atoms, clump size,
periodic, box), which cases.json's `scene_*` cases read.

Conversions: the charge of an atom is its q (charges-box, dipoles, platelets) or its mass
(gravity-collapse: gravity = coulomb of charges equal to the masses with the sign flipped;
the relative force error of a linear solver is the same). Atoms are renumbered so that the
pebbles of a clump (molecule ID) are consecutive, so bench_solvers --clump K groups them.
The scenes' dielectric is not copied: the benchmark uses dielectric 1 (relative errors do not
depend on it).
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))

# name: (example directory, input, dump columns, charge column, molecule column or None)
SCENES = {
    "charges-box": ("charges-box", "in.charges-box", "id q x y z", "q", None),
    "dipoles": ("dipoles", "in.dipoles", "id mol q x y z", "q", "mol"),
    "gravity-collapse": ("gravity-collapse", "in.gravity-collapse", "id mass x y z", "mass",
                         None),
    "platelets": ("platelets", "in.platelets", "id mol q x y z", "q", "mol"),
}


def instrument(text, columns):
    """Adds the two snapshot dumps to an example input."""
    lines = text.splitlines()
    start = None
    for i, ln in enumerate(lines):
        if re.match(r"^run\s+0\s*(#.*)?$", ln):
            start = i
    if start is None:
        raise ValueError("no plain 'run 0' line (start of the production run) in the input")
    dump = "write_dump all custom out/bench-{0}.dump " + columns + " modify sort id"
    lines.insert(start + 1, dump.format("start"))
    lines.append(dump.format("end"))
    return "\n".join(lines) + "\n"


def read_dump(path):
    with open(path) as f:
        lines = f.read().splitlines()
    i = lines.index("ITEM: NUMBER OF ATOMS")
    n = int(lines[i + 1])
    b = next(k for k, ln in enumerate(lines) if ln.startswith("ITEM: BOX BOUNDS"))
    flags = lines[b].split()[3:6]
    box = [[float(v) for v in lines[b + 1 + d].split()[:2]] for d in range(3)]
    a = next(k for k, ln in enumerate(lines) if ln.startswith("ITEM: ATOMS"))
    cols = lines[a].split()[2:]
    rows = [dict(zip(cols, ln.split())) for ln in lines[a + 1:a + 1 + n]]
    return rows, box, all(f == "pp" for f in flags)


def convert(dump, out_data, charge_col, mol_col):
    rows, box, periodic = read_dump(dump)
    if mol_col:
        rows.sort(key=lambda r: (int(r[mol_col]), int(r["id"])))
        sizes = {}
        for r in rows:
            sizes[r[mol_col]] = sizes.get(r[mol_col], 0) + 1
        ks = set(sizes.values())
        clump = ks.pop() if len(ks) == 1 else 1    # unequal clumps: no clump errors
    else:
        rows.sort(key=lambda r: int(r["id"]))
        clump = 1
    with open(out_data, "w") as f:
        f.write(f"scene snapshot from {os.path.basename(dump)}\n\n{len(rows)} atoms\n"
                "1 atom types\n\n")
        for d, ax in enumerate("xyz"):
            f.write(f"{box[d][0]:.17g} {box[d][1]:.17g} {ax}lo {ax}hi\n")
        f.write("\nMasses\n\n1 1\n\nAtoms # charge\n\n")
        for k, r in enumerate(rows, 1):
            f.write(f"{k} 1 {float(r[charge_col]):.17g} {r['x']} {r['y']} {r['z']}\n")
    qnet = sum(float(r[charge_col]) for r in rows)
    return {"natoms": len(rows), "clump": clump, "periodic": periodic,
            "box": box, "net_charge": qnet, "charge": charge_col}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lmp", required=True, help="lmp_kifmm executable")
    ap.add_argument("--work", required=True)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--full", action="store_true", help="full-size variants (hours)")
    ap.add_argument("--timeout", type=float, default=3600)
    args = ap.parse_args()
    outdir = os.path.join(args.work, "scenes")
    os.makedirs(outdir, exist_ok=True)
    env = dict(os.environ)
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    env.setdefault("KIFMM_CACHE_DIR", os.path.join(args.work, "operator-cache"))
    rc = 0
    for name in filter(None, args.scenes.split(",")):
        exdir, inp, cols, qcol, mcol = SCENES[name]
        done = all(os.path.exists(os.path.join(outdir, f"{name}_{s}.json"))
                   for s in ("start", "end"))
        if done:
            continue
        run = os.path.join(outdir, name)
        shutil.rmtree(run, ignore_errors=True)
        shutil.copytree(os.path.join(ROOT, "examples", exdir), run,
                        ignore=shutil.ignore_patterns("out", "full-run"))
        with open(os.path.join(run, inp)) as f:
            text = f.read()
        with open(os.path.join(run, inp), "w") as f:
            f.write(instrument(text, cols))
        cmd = [args.lmp, "-in", inp, "-var", "quick", "0" if args.full else "1",
               "-var", "potentials", os.path.join(ROOT, "potentials"), "-log", "log.lammps",
               "-screen", "none", "-nocite"]
        t0 = time.time()
        p = subprocess.run(cmd, cwd=run, env=env, timeout=args.timeout)
        if p.returncode != 0:
            print(f"scene {name}: lmp_kifmm failed (exit {p.returncode}), see {run}/log.lammps")
            rc = 1
            continue
        for state in ("start", "end"):
            meta = convert(os.path.join(run, "out", f"bench-{state}.dump"),
                           os.path.join(outdir, f"{name}_{state}.data"), qcol, mcol)
            meta.update({"scene": name, "state": state,
                         "variant": "full" if args.full else "quick",
                         "scene_wall_s": time.time() - t0})
            with open(os.path.join(outdir, f"{name}_{state}.json"), "w") as f:
                json.dump(meta, f)
        print(f"scene {name}: {meta['natoms']} atoms, clump {meta['clump']}, "
              f"{'periodic' if meta['periodic'] else 'open'}, {time.time() - t0:.0f} s")
    return rc


if __name__ == "__main__":
    sys.exit(main())
