#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Chains and rings in the frames of out/spheres.dump (written by in.magnetic-chains).

Two spheres touch when their centres are closer than --contact diameters (open box). A contact
is head to tail when both dipoles lie within 45 degrees of the line of centres
(|mu . r| > 0.7 |mu| |r| for both); side-by-side contacts (of neighbouring chains) are not. The
clusters of spheres linked by head-to-tail contacts are sorted by shape: a chain is a cluster
of at least 3 spheres in which no sphere has more than two such links and which has no loop; a
ring is one in which every sphere has exactly two (one closed loop); the rest are pairs,
single spheres and branched clusters. Head to tail: over all contacts, |mu_i . r| / (|mu_i|
|r|) averaged over both spheres (1: dipoles along the line of centres). Per frame:
  time, fraction of spheres in chains, in rings, number of chains, number of rings,
  head-to-tail alignment, mean height of the centres
Writes out/structures.dat and prints the first and last rows.

usage: python3 structures.py [OUTDIR] [--d D] [--dt DT] [--contact C]
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import kifmm_dumps  # noqa: E402

HEAD_TO_TAIL = math.cos(math.radians(45.0))


def analyse(rows, d, contact):
    n = len(rows)
    cut = contact * d
    grid = {}
    for k, r in enumerate(rows):
        grid.setdefault(tuple(int(math.floor(r[a] / cut)) for a in range(3)), []).append(k)
    nbr = [[] for _ in range(n)]
    align, nalign = 0.0, 0
    for k, r in enumerate(rows):
        c = [int(math.floor(r[a] / cut)) for a in range(3)]
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for j in grid.get((c[0] + dx, c[1] + dy, c[2] + dz), ()):
                        if j <= k:
                            continue
                        v = [r[a] - rows[j][a] for a in range(3)]
                        dist = math.sqrt(sum(x * x for x in v))
                        if dist >= cut:
                            continue
                        cosines = []
                        for m in (r[3:6], rows[j][3:6]):
                            mm = math.sqrt(sum(x * x for x in m))
                            cosines.append(abs(sum(m[a] * v[a] for a in range(3))) / (mm * dist) if mm > 0 else 0.0)
                        align += sum(cosines)
                        nalign += 2
                        if min(cosines) > HEAD_TO_TAIL:
                            nbr[k].append(j)
                            nbr[j].append(k)
    seen = [False] * n
    in_chains = in_rings = chains = rings = 0
    for k in range(n):
        if seen[k]:
            continue
        stack, members = [k], []
        seen[k] = True
        while stack:
            a = stack.pop()
            members.append(a)
            for b in nbr[a]:
                if not seen[b]:
                    seen[b] = True
                    stack.append(b)
        size = len(members)
        degrees = [len(nbr[a]) for a in members]
        edges = sum(degrees) // 2
        if size >= 3 and all(g == 2 for g in degrees) and edges == size:
            rings += 1
            in_rings += size
        elif size >= 3 and max(degrees) <= 2 and edges == size - 1:
            chains += 1
            in_chains += size
    zmean = sum(r[2] for r in rows) / n
    return (in_chains / n, in_rings / n, chains, rings, align / nalign if nalign else 0.0, zmean)


def table(outdir, d=1.0, dt=0.002, contact=1.1):
    out = []
    for step, _, rows in kifmm_dumps.frames(os.path.join(outdir, "spheres.dump"),
                                            ("x", "y", "z", "mux", "muy", "muz")):
        if out and abs(out[-1][0] - step * dt) < 1e-12:
            continue    # the first frame of a run repeats the last of the one before
        out.append((step * dt,) + analyse(rows, d, contact))
    return out


def describe(r):
    return (f"t = {r[0]:g}: in chains {r[1]:.3f} ({r[3]} chains), in rings {r[2]:.3f} ({r[4]} rings), "
            f"head-to-tail {r[5]:.3f}, mean height {r[6]:.3f}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir", nargs="?", default="out")
    ap.add_argument("--d", type=float, default=1.0)
    ap.add_argument("--dt", type=float, default=0.002)
    ap.add_argument("--contact", type=float, default=1.1)
    a = ap.parse_args()
    rows = table(a.outdir, a.d, a.dt, a.contact)
    with open(os.path.join(a.outdir, "structures.dat"), "w") as f:
        f.write("# time in_chains in_rings chains rings head_to_tail z_mean\n")
        for r in rows:
            f.write(" ".join(f"{v:.6g}" for v in r) + "\n")
    print(describe(rows[0]))
    print(describe(rows[-1]))


if __name__ == "__main__":
    main()
