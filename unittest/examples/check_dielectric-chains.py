#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/dielectric-chains from its outputs (out/spheres.dump,
out/energy.dat).

Asserts: at the start few spheres are in field-aligned chains (at most --max-start), at the
end most are (at least --min-end) and the contacts are ordered along the field (p2 at least
--min-p2; 0 is isotropic); the sum of the long-range, polarization, field and kinetic
energies never rises (the drag and the contact damping only remove energy) by more than
--rise of its size, and it has fallen; the solve for the induced dipoles took at most
--max-iterations per step. The chain measures are those of examples/dielectric-chains/chains.py.

usage: check_dielectric-chains.py OUTDIR [--max-start F] [--min-end F] [--min-p2 P]
                                  [--rise R] [--max-iterations N]
"""
import argparse
import os
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--max-start", type=float, default=0.15)
    ap.add_argument("--min-end", type=float, default=0.7)
    ap.add_argument("--min-p2", type=float, default=0.4)
    ap.add_argument("--rise", type=float, default=1e-4)
    ap.add_argument("--max-iterations", type=int, default=10)
    a = ap.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, os.path.join(here, "..", "..", "examples", "dielectric-chains"))
    import chains  # the example's own analysis (examples/dielectric-chains/chains.py)

    ok = True
    rows = chains.table(a.outdir)
    first, last = rows[0], rows[-1]
    print(f"frames {len(rows)}; t = {first[0]:g}: aligned {first[1]:.3f}, p2 {first[2]:.3f}; "
          f"t = {last[0]:g}: aligned {last[1]:.3f}, p2 {last[2]:.3f}, spanning {last[3]:.3f}")
    if first[1] > a.max_start:
        print(f"FAIL: {first[1]:.3f} of the spheres in aligned chains at the start > {a.max_start}")
        ok = False
    if last[1] < a.min_end:
        print(f"FAIL: {last[1]:.3f} of the spheres in aligned chains at the end < {a.min_end}")
        ok = False
    if last[2] < a.min_p2:
        print(f"FAIL: contact order p2 {last[2]:.3f} at the end < {a.min_p2}")
        ok = False

    head, table = None, []
    with open(os.path.join(a.outdir, "energy.dat")) as f:
        for line in f:
            if line.startswith("#"):
                head = head or line.split()[1:]
                continue
            if line.strip():
                table.append([float(v) for v in line.split()])
    col = {name: k for k, name in enumerate(head)}
    total = [sum(r[col[c]] for c in ("U_LR", "U_pol", "U_field", "U_kin")) for r in table]
    scale = max(abs(u) for u in total)
    rise = max((b - a_) for a_, b in zip(total, total[1:]))
    iters = max(r[col["iterations"]] for r in table)
    print(f"total energy {total[0]:.6g} -> {total[-1]:.6g}, largest rise {rise:.3g} ({rise / scale:.2e} of "
          f"its size); most iterations of a solve {iters:g}")
    if rise > a.rise * scale:
        print(f"FAIL: the total energy rose by {rise / scale:.2e} of its size > {a.rise}")
        ok = False
    if not total[-1] < total[0]:
        print("FAIL: the total energy did not fall")
        ok = False
    if iters > a.max_iterations:
        print(f"FAIL: a solve took {iters:g} iterations > {a.max_iterations}")
        ok = False
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
