#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/charged-floor from its outputs (out/final.dump).

Asserts: at least --min-floor of the spheres lie on the floor (centre below 1.5 r), and the
spheres on the floor are spread evenly over it: the in-plane distance of every one to its
nearest neighbour (through the periodic x and y faces) is at least --min-nn times the spacing
a = sqrt(2 A / (sqrt(3) N)) of a triangular lattice of the same density, and the nearest-
neighbour distances vary little (coefficient of variation at most --max-cv). For comparison
the script prints what uniformly random positions of the same number give (no repulsion:
nearest neighbours down to contact, coefficient of variation about 0.5).

usage: check_charged-floor.py OUTDIR [--radius R] [--lx LX] [--ly LY] [--min-floor F]
                              [--min-nn X] [--max-cv C]
"""
import argparse
import math
import os
import random
import sys


def read_dump(path):
    with open(path) as f:
        lines = f.read().splitlines()
    i = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[i].split()[2:]
    ix, iy, iz = cols.index("x"), cols.index("y"), cols.index("z")
    return [(float(p[ix]), float(p[iy]), float(p[iz])) for p in (l.split() for l in lines[i + 1:]) if p]


def nearest(pts, lx, ly):
    out = []
    for i, (x, y) in enumerate(pts):
        best = float("inf")
        for j, (u, v) in enumerate(pts):
            if i == j:
                continue
            dx = x - u - lx * round((x - u) / lx)
            dy = y - v - ly * round((y - v) / ly)
            best = min(best, math.hypot(dx, dy))
        out.append(best)
    return out


def stats(nn):
    m = sum(nn) / len(nn)
    sd = math.sqrt(sum((d - m) ** 2 for d in nn) / len(nn))
    return min(nn), m, sd / m


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--radius", type=float, default=0.01)
    ap.add_argument("--lx", type=float, default=1.0)
    ap.add_argument("--ly", type=float, default=1.0)
    ap.add_argument("--min-floor", type=float, default=0.95)
    ap.add_argument("--min-nn", type=float, default=0.5)
    ap.add_argument("--max-cv", type=float, default=0.2)
    a = ap.parse_args()
    pts = read_dump(os.path.join(a.outdir, "final.dump"))
    floor = [(x, y) for x, y, z in pts if z < 1.5 * a.radius]
    frac = len(floor) / len(pts)
    spacing = math.sqrt(2 * a.lx * a.ly / (math.sqrt(3) * len(floor))) if floor else 0.0
    ok = True
    print(f"spheres = {len(pts)}, on the floor = {len(floor)} (fraction {frac:.3f})")
    if frac < a.min_floor:
        print(f"FAIL: fraction on the floor {frac:.3f} < {a.min_floor}")
        ok = False
    if len(floor) > 1:
        mn, mean, cv = stats(nearest(floor, a.lx, a.ly))
        rnd = random.Random(1)
        rmn, rmean, rcv = stats(nearest([(rnd.uniform(0, a.lx), rnd.uniform(0, a.ly)) for _ in floor], a.lx, a.ly))
        print(f"triangular lattice spacing a = {spacing:.4g}")
        print(f"nearest neighbour: min {mn / spacing:.3f} a, mean {mean / spacing:.3f} a, coefficient of variation {cv:.3f}")
        print(f"(uniformly random positions: min {rmn / spacing:.3f} a, mean {rmean / spacing:.3f} a, "
              f"coefficient of variation {rcv:.3f})")
        if mn < a.min_nn * spacing:
            print(f"FAIL: closest pair {mn / spacing:.3f} a < {a.min_nn} a")
            ok = False
        if cv > a.max_cv:
            print(f"FAIL: coefficient of variation {cv:.3f} > {a.max_cv}")
            ok = False
    print("PASS" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
