#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/magnetic-chains from its outputs (out/spheres.dump,
out/energy.dat).

Asserts, at the end: the spheres have settled on the floor (mean centre height at most
--max-height diameters), at least --min-linked of them are in chains or rings, there are at
least --min-rings rings, the contacts are head to tail (alignment at least --min-align; 1:
dipoles along the lines of centres), and the dipole energy U_LR has fallen to at most
--max-ulr times its start (it starts near zero or positive from random orientations, so: below
zero). The measures are those of examples/magnetic-chains/structures.py.

usage: check_magnetic-chains.py OUTDIR [--max-height H] [--min-linked F] [--min-rings N]
                                [--min-align A]
"""
import argparse
import os
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--max-height", type=float, default=0.6)
    ap.add_argument("--min-linked", type=float, default=0.6)
    ap.add_argument("--min-rings", type=int, default=1)
    ap.add_argument("--min-align", type=float, default=0.85)
    a = ap.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, os.path.join(here, "..", "..", "examples", "magnetic-chains"))
    import structures  # the example's own analysis (examples/magnetic-chains/structures.py)

    rows = structures.table(a.outdir)
    first, last = rows[0], rows[-1]
    print(structures.describe(first))
    print(structures.describe(last))
    ulr = []
    with open(os.path.join(a.outdir, "energy.dat")) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                ulr.append(float(line.split()[1]))
    print(f"U_LR {ulr[0]:.6g} -> {ulr[-1]:.6g}")
    ok = True
    checks = [
        (last[6] <= a.max_height, f"mean height {last[6]:.3f} > {a.max_height}: not settled"),
        (last[1] + last[2] >= a.min_linked, f"{last[1] + last[2]:.3f} of the spheres in chains or rings < {a.min_linked}"),
        (last[4] >= a.min_rings, f"{last[4]} rings < {a.min_rings}"),
        (last[5] >= a.min_align, f"head-to-tail alignment {last[5]:.3f} < {a.min_align}"),
        (ulr[-1] < 0 and ulr[-1] < ulr[0], "the dipole energy did not fall below zero"),
    ]
    for good, why in checks:
        if not good:
            print("FAIL:", why)
            ok = False
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
