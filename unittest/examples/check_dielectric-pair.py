#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/dielectric-pair from its output (out/forces.dat).

Asserts: at every gap the force from the surface charge (fix kifmm/dielectric) is within
--tolerance of the exact force of two dielectric spheres (examples/dielectric-pair/
two_spheres.py, the multipole solution), the force grows as the gap closes, and at touching
the point-dipole model is off by more than a factor --min-factor.

usage: check_dielectric-pair.py OUTDIR [--tolerance T] [--min-factor F]
"""
import argparse
import os
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--min-factor", type=float, default=4.0)
    a = ap.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, os.path.join(here, "..", "..", "examples", "dielectric-pair"))
    import two_spheres  # the exact solution (examples/dielectric-pair/two_spheres.py)

    with open(os.path.join(a.outdir, "forces.dat")) as f:
        lines = f.read().splitlines()
    head = lines[0].split()
    par = dict(zip(head[1::2], map(float, head[2::2])))
    rows = [list(map(float, l.split())) for l in lines if l.strip() and not l.startswith("#")]
    ok = len(rows) >= 3
    previous = 0.0
    for gap, d, fs, fp, ratio, steps, u in rows:
        exact = two_spheres.force(par["a"], d, par["eps"], par["E"])
        err = fs / exact - 1
        print(f"gap {gap:g}: surface {fs:.6g}, exact {exact:.6g} (error {err:+.2e}), point dipoles {fp:.6g} "
              f"(exact / point dipoles {exact / fp:.3f}), GMRES steps {steps:g}")
        if abs(err) > a.tolerance:
            print(f"FAIL: the surface force is off by {err:+.2e} > {a.tolerance}")
            ok = False
        if fs <= previous:
            print("FAIL: the force does not grow as the gap closes")
            ok = False
        previous = fs
    touching = [r for r in rows if r[0] == 0.0]
    if not touching:
        print("FAIL: no row for touching spheres")
        ok = False
    else:
        gap, d, fs, fp = touching[0][:4]
        factor = two_spheres.force(par["a"], d, par["eps"], par["E"]) / fp
        if factor < a.min_factor:
            print(f"FAIL: at touching the exact force is only {factor:.2f} times the point-dipole model's")
            ok = False
    print("PASS" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
