#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Chains along the field in the frames of out/spheres.dump (written by in.dielectric-chains).

Two spheres touch when their centres are closer than --contact diameters (periodic in x, y and
z, the box of the dump). A contact is aligned with the field (z) when the line of centres is
within 30 degrees of z. Per frame:
  aligned   fraction of spheres with at least one aligned contact (in a field-aligned chain)
  p2        order of all contacts, <(3 cos^2 theta - 1) / 2> (0: isotropic, 1: all along z)
  spanning  fraction of spheres in clusters of aligned contacts that touch both electrodes
            (a sphere within 0.1 d of the wall at z = 0 and one at z = H)
Writes out/chains.dat (time, aligned, p2, spanning) and prints the first and last rows.

usage: python3 chains.py [OUTDIR] [--d D] [--H H] [--dt DT] [--contact C]
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import kifmm_dumps  # noqa: E402

COS30 = math.cos(math.radians(30.0))


def analyse(box, pts, d, H, contact):
    n = len(pts)
    cell = contact * d
    grid = {}
    for k, p in enumerate(pts):
        grid.setdefault(tuple(int(math.floor(p[a] / cell)) for a in range(3)), []).append(k)
    ncell = [max(1, int(math.floor(box[a] / cell))) for a in range(3)]
    aligned = [0] * n
    parent = list(range(n))

    def find(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    p2sum, ncontact = 0.0, 0
    for k, p in enumerate(pts):
        c = [int(math.floor(p[a] / cell)) for a in range(3)]
        seen = set()
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    key = ((c[0] + dx) % ncell[0], (c[1] + dy) % ncell[1], (c[2] + dz) % ncell[2])
                    if key in seen:
                        continue
                    seen.add(key)
                    for j in grid.get(key, ()):
                        if j <= k:
                            continue
                        r = [p[a] - pts[j][a] for a in range(3)]
                        r = [r[a] - box[a] * round(r[a] / box[a]) for a in range(3)]
                        dist = math.sqrt(sum(v * v for v in r))
                        if dist >= contact * d:
                            continue
                        cz = abs(r[2]) / dist
                        p2sum += 1.5 * cz * cz - 0.5
                        ncontact += 1
                        if cz > COS30:
                            aligned[k] = aligned[j] = 1
                            parent[find(k)] = find(j)
    lo, hi = {}, {}
    for k, p in enumerate(pts):
        root = find(k)
        lo[root] = lo.get(root, False) or p[2] < 0.6 * d
        hi[root] = hi.get(root, False) or p[2] > H - 0.6 * d
    spanning = sum(1 for k in range(n) if aligned[k] and lo[find(k)] and hi[find(k)])
    return sum(aligned) / n, (p2sum / ncontact if ncontact else 0.0), spanning / n


def table(outdir, d=1.0, H=8.0, dt=0.002, contact=1.1):
    rows = []
    for step, box, pts in kifmm_dumps.frames(os.path.join(outdir, "spheres.dump"), ("x", "y", "z")):
        if rows and abs(rows[-1][0] - step * dt) < 1e-12:
            continue    # the first frame of a run repeats the last of the one before
        rows.append((step * dt,) + analyse(box, pts, d, H, contact))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir", nargs="?", default="out")
    ap.add_argument("--d", type=float, default=1.0)
    ap.add_argument("--H", type=float, default=8.0)
    ap.add_argument("--dt", type=float, default=0.002)
    ap.add_argument("--contact", type=float, default=1.1)
    a = ap.parse_args()
    rows = table(a.outdir, a.d, a.H, a.dt, a.contact)
    with open(os.path.join(a.outdir, "chains.dat"), "w") as f:
        f.write("# time aligned p2 spanning\n")
        for r in rows:
            f.write(" ".join(f"{v:.6g}" for v in r) + "\n")
    for r in (rows[0], rows[-1]):
        print(f"t = {r[0]:g}: in aligned chains {r[1]:.3f}, contact order p2 {r[2]:.3f}, spanning the gap {r[3]:.3f}")


if __name__ == "__main__":
    main()
