#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/dipoles from its outputs.

Asserts: the largest aggregate (clumps connected through pebble
contacts, pebble centres of different clumps closer than 2.04 r) grows to many clumps, and the
centre of mass falls. Thresholds (defaults): largest aggregate >= 20 clumps in the last frame
of out/clumps.dump and at least 5x its size in the first frame; zcm/L at the end below its
start by more than 0.02 (out/energy.dat).

usage: check_dipoles.py OUTDIR [--radius R] [--min-largest 20] [--min-growth 5] [--min-fall 0.02]
"""
import argparse
import os
import sys


def read_frames(path):
    """List of (timestep, [(mol, x, y, z), ...]) of a LAMMPS text dump."""
    frames = []
    with open(path) as f:
        lines = f.read().splitlines()
    k = 0
    while k < len(lines):
        if lines[k].startswith("ITEM: TIMESTEP"):
            step = int(lines[k + 1])
            n = int(lines[k + 3])
            cols = lines[k + 8].split()[2:]
            im, ix, iy, iz = (cols.index(c) for c in ("mol", "x", "y", "z"))
            pebbles = []
            for l in lines[k + 9:k + 9 + n]:
                p = l.split()
                pebbles.append((int(p[im]), float(p[ix]), float(p[iy]), float(p[iz])))
            frames.append((step, pebbles))
            k += 9 + n
        else:
            k += 1
    return frames


def largest_aggregate(pebbles, cut):
    """Size (in clumps) of the largest set of clumps connected by pebble contacts."""
    parent = {}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for m, *_ in pebbles:
        parent[m] = m
    cells = {}
    for k, (m, x, y, z) in enumerate(pebbles):
        cells.setdefault((int(x // cut), int(y // cut), int(z // cut)), []).append(k)
    cut2 = cut * cut
    for (cx, cy, cz), members in cells.items():
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    other = cells.get((cx + dx, cy + dy, cz + dz))
                    if not other:
                        continue
                    for i in members:
                        mi, xi, yi, zi = pebbles[i]
                        for j in other:
                            if j <= i:
                                continue
                            mj, xj, yj, zj = pebbles[j]
                            if mi == mj:
                                continue
                            if (xi - xj) ** 2 + (yi - yj) ** 2 + (zi - zj) ** 2 < cut2:
                                a, b = find(mi), find(mj)
                                if a != b:
                                    parent[a] = b
    sizes = {}
    for m in parent:
        r = find(m)
        sizes[r] = sizes.get(r, 0) + 1
    return max(sizes.values()), len(parent)


def read_energy(path):
    rows = []
    with open(path) as f:
        head = f.readline().split()[1:]
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append([float(v) for v in line.split()])
    return head, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--radius", type=float, default=0.005)
    ap.add_argument("--min-largest", type=int, default=20)
    ap.add_argument("--min-growth", type=float, default=5.0)
    ap.add_argument("--min-fall", type=float, default=0.02)
    a = ap.parse_args()
    frames = read_frames(os.path.join(a.outdir, "clumps.dump"))
    l0, _ = largest_aggregate(frames[0][1], 2.04 * a.radius)
    largest, nclumps = largest_aggregate(frames[-1][1], 2.04 * a.radius)
    head, rows = read_energy(os.path.join(a.outdir, "energy.dat"))
    iz = head.index("zcm/L")
    z0, z1 = rows[0][iz], rows[-1][iz]
    print(f"clumps = {nclumps}, largest aggregate at step {frames[0][0]} = {l0}, "
          f"at step {frames[-1][0]} = {largest}")
    print(f"centre of mass height zcm/L: start {z0:.4f}, end {z1:.4f}, fall {z0 - z1:.4f}")
    ok = True
    if largest < a.min_largest:
        print(f"FAIL: largest aggregate {largest} < {a.min_largest} clumps")
        ok = False
    if largest < a.min_growth * max(l0, 1):
        print(f"FAIL: largest aggregate grew only from {l0:g} to {largest}")
        ok = False
    if not z0 - z1 > a.min_fall:
        print(f"FAIL: centre of mass fell by {z0 - z1:.4f} <= {a.min_fall}")
        ok = False
    print("PASS" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
