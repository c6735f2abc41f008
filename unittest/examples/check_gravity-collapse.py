#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/gravity-collapse from its outputs.

Asserts: the radius of gyration falls by more than 3x (first row of
out/energy.dat against out/final.dump) and the final ball is nearly spherical: the axis
ratio sqrt(lambda_min / lambda_max) of the gyration tensor of all spheres exceeds 0.8.

usage: check_gravity-collapse.py OUTDIR [--min-ratio 3] [--min-axis 0.8]
"""
import argparse
import math
import os
import sys


def read_dump(path):
    with open(path) as f:
        lines = f.read().splitlines()
    i = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[i].split()[2:]
    ix, iy, iz = cols.index("x"), cols.index("y"), cols.index("z")
    return [(float(p[ix]), float(p[iy]), float(p[iz]))
            for p in (l.split() for l in lines[i + 1:]) if p]


def eig_sym3(a):
    """Eigenvalues of a symmetric 3x3 matrix (list of lists) by cyclic Jacobi rotations."""
    a = [row[:] for row in a]
    for _ in range(100):
        off = sum(a[p][q] ** 2 for p in range(3) for q in range(3) if p != q)
        if off < 1e-30 * max(1e-300, sum(a[k][k] ** 2 for k in range(3))):
            break
        for p, q in ((0, 1), (0, 2), (1, 2)):
            if a[p][q] == 0.0:
                continue
            theta = (a[q][q] - a[p][p]) / (2 * a[p][q])
            t = math.copysign(1.0, theta) / (abs(theta) + math.sqrt(theta * theta + 1))
            c = 1 / math.sqrt(t * t + 1)
            s = t * c
            for k in range(3):  # columns p, q
                akp, akq = a[k][p], a[k][q]
                a[k][p], a[k][q] = c * akp - s * akq, s * akp + c * akq
            for k in range(3):  # rows p, q
                apk, aqk = a[p][k], a[q][k]
                a[p][k], a[q][k] = c * apk - s * aqk, s * apk + c * aqk
    return sorted(a[k][k] for k in range(3))


def gyration(pts):
    n = len(pts)
    c = [sum(p[k] for p in pts) / n for k in range(3)]
    g = [[sum((p[i] - c[i]) * (p[j] - c[j]) for p in pts) / n for j in range(3)] for i in range(3)]
    lam = eig_sym3(g)
    return math.sqrt(sum(lam)), lam


def first_rg(path):
    with open(path) as f:
        head = f.readline().split()[1:]
        col = head.index("Rg")
        for line in f:
            if line.strip() and not line.startswith("#"):
                return float(line.split()[col])
    raise RuntimeError("no data in " + path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--min-ratio", type=float, default=3.0)
    ap.add_argument("--min-axis", type=float, default=0.8)
    a = ap.parse_args()
    rg0 = first_rg(os.path.join(a.outdir, "energy.dat"))
    rg, lam = gyration(read_dump(os.path.join(a.outdir, "final.dump")))
    ratio = rg0 / rg
    axis = math.sqrt(lam[0] / lam[2])
    print(f"Rg initial = {rg0:.4g}, final = {rg:.4g}, ratio = {ratio:.3f}")
    print(f"gyration eigenvalues = {lam[0]:.4g} {lam[1]:.4g} {lam[2]:.4g}, axis ratio = {axis:.3f}")
    ok = True
    if not ratio > a.min_ratio:
        print(f"FAIL: Rg ratio {ratio:.3f} <= {a.min_ratio}")
        ok = False
    if not axis > a.min_axis:
        print(f"FAIL: axis ratio {axis:.3f} <= {a.min_axis}")
        ok = False
    print("PASS" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
