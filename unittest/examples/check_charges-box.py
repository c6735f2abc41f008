#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/charges-box from its outputs (out/final.dump).

Asserts: the fraction of spheres whose centre is within 2r of a wall
exceeds 0.9, and the edge regions of the walls are denser than the face centres.

Wall spheres (centre within 2r of a wall) are assigned to their nearest wall and located by
their two in-plane coordinates (u, v) in [0, 1]^2. Edge band: min(u, 1-u, v, 1-v) < 0.1
(area 0.36 per face, corners included). Face centre: max(|u-0.5|, |v-0.5|) < 0.25 (area 0.25).
Densities are counts per unit wall area summed over the six faces.

usage: check_charges_box.py OUTDIR [--radius R] [--min-fraction F] [--min-ratio X]
"""
import argparse
import os
import sys


def read_dump(path):
    with open(path) as f:
        lines = f.read().splitlines()
    i = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[i].split()[2:]
    ix, iy, iz = cols.index("x"), cols.index("y"), cols.index("z")
    pts = []
    for l in lines[i + 1:]:
        p = l.split()
        if p:
            pts.append((float(p[ix]), float(p[iy]), float(p[iz])))
    return pts


def analyse(pts, r, edge=0.1, centre=0.25):
    n = len(pts)
    wall = 0
    n_edge = n_centre = 0
    for x, y, z in pts:
        cand = [(x, 0), (1 - x, 0), (y, 1), (1 - y, 1), (z, 2), (1 - z, 2)]
        d, axis = min(cand)
        if d >= 2 * r:
            continue
        wall += 1
        c = (x, y, z)
        u, v = [c[k] for k in range(3) if k != axis]
        if min(u, 1 - u, v, 1 - v) < edge:
            n_edge += 1
        if max(abs(u - 0.5), abs(v - 0.5)) < centre:
            n_centre += 1
    area_edge = 6 * (1 - (1 - 2 * edge) ** 2)
    area_centre = 6 * (2 * centre) ** 2
    rho_edge = n_edge / area_edge
    rho_centre = n_centre / area_centre
    return {
        "atoms": n,
        "wall_fraction": wall / n,
        "edge_density": rho_edge,
        "centre_density": rho_centre,
        "edge_to_centre": rho_edge / rho_centre if rho_centre > 0 else float("inf"),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--radius", type=float, default=0.0025)
    ap.add_argument("--min-fraction", type=float, default=0.9)
    ap.add_argument("--min-ratio", type=float, default=1.0)
    a = ap.parse_args()
    res = analyse(read_dump(os.path.join(a.outdir, "final.dump")), a.radius)
    for k, v in res.items():
        print(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}")
    ok = True
    if not res["wall_fraction"] > a.min_fraction:
        print(f"FAIL: fraction within 2r of a wall {res['wall_fraction']:.4f} <= {a.min_fraction}")
        ok = False
    if not res["edge_to_centre"] > a.min_ratio:
        print(f"FAIL: edge density / face-centre density {res['edge_to_centre']:.3f} <= {a.min_ratio}")
        ok = False
    print("PASS" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
