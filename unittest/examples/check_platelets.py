#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Check the outcome of examples/platelets from its outputs (out/pebbles.dump).

Asserts: the platelet normals stay aligned (nematic order parameter
S > 0.9 in the last frame) and the nearest-platelet spacing shrinks to near contact (mean over
platelets of the distance to the nearest other platelet's centre, in the last frame, below
1.5 x the platelet thickness h + 2r = 0.026 and below 0.6 x its value in the first frame).
The normals are not required to stay aligned at every frame: the co-oriented start is unstable
(the platelets tumble, as the paper's large rotational kinetic energy shows) and the alignment
is recovered when the platelets close the column through the periodic boundary
(examples/platelets/README.md).

Each platelet's normal is the direction from the centroid of its negative pebbles to the
centroid of its positive ones (its dipole axis); S is the largest eigenvalue of
Q = <(3 n n^T - I) / 2>. The polar order |<n>| is printed too. Periodic dimensions (pp in the
dump's box line) use minimum-image distances, within a platelet and between centres.

usage: check_platelets.py OUTDIR [--thickness 0.026] [--min-order 0.9]
                                 [--max-spacing-factor 1.5] [--max-shrink 0.6]
"""
import argparse
import math
import os
import sys


def read_frames(path):
    """List of (step, box lengths, periodic flags, {mol: [(q, x, y, z), ...]})."""
    frames = []
    with open(path) as f:
        lines = f.read().splitlines()
    k = 0
    while k < len(lines):
        if not lines[k].startswith("ITEM: TIMESTEP"):
            k += 1
            continue
        step = int(lines[k + 1])
        n = int(lines[k + 3])
        flags = lines[k + 4].split()[3:6]
        lo_hi = [tuple(map(float, lines[k + 5 + d].split()[:2])) for d in range(3)]
        box = [hi - lo for lo, hi in lo_hi]
        periodic = [fl.startswith("p") for fl in flags]
        cols = lines[k + 8].split()[2:]
        im, iq, ix, iy, iz = (cols.index(c) for c in ("mol", "q", "x", "y", "z"))
        mols = {}
        for line in lines[k + 9:k + 9 + n]:
            p = line.split()
            mols.setdefault(int(p[im]), []).append(
                (float(p[iq]), float(p[ix]), float(p[iy]), float(p[iz])))
        frames.append((step, box, periodic, mols))
        k += 9 + n
    return frames


def wrap(d, box, periodic):
    return [d[a] - box[a] * round(d[a] / box[a]) if periodic[a] else d[a] for a in range(3)]


def platelets(box, periodic, mols):
    """Centre and unit normal (dipole axis, - to +) of each platelet."""
    out = []
    for mol in sorted(mols):
        peb = mols[mol]
        ref = peb[0][1:]
        pos = [[ref[a] + w for a, w in enumerate(wrap([p[1 + a] - ref[a] for a in range(3)],
                                                        box, periodic))] for p in peb]
        c = [sum(p[a] for p in pos) / len(pos) for a in range(3)]
        plus = [p for p, q in zip(pos, peb) if q[0] > 0]
        minus = [p for p, q in zip(pos, peb) if q[0] < 0]
        cp = [sum(p[a] for p in plus) / len(plus) for a in range(3)]
        cm = [sum(p[a] for p in minus) / len(minus) for a in range(3)]
        d = [cp[a] - cm[a] for a in range(3)]
        norm = math.sqrt(sum(x * x for x in d))
        out.append((c, [x / norm for x in d]))
    return out


def largest_eig_sym3(a):
    """Largest eigenvalue of a symmetric 3x3 matrix, closed form."""
    q = (a[0][0] + a[1][1] + a[2][2]) / 3
    p1 = a[0][1] ** 2 + a[0][2] ** 2 + a[1][2] ** 2
    p2 = sum((a[i][i] - q) ** 2 for i in range(3)) + 2 * p1
    p = math.sqrt(p2 / 6)
    if p == 0:
        return q
    b = [[(a[i][j] - (q if i == j else 0)) / p for j in range(3)] for i in range(3)]
    det = (b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1])
           - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
           + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]))
    r = max(-1.0, min(1.0, det / 2))
    return q + 2 * p * math.cos(math.acos(r) / 3)


def order(normals):
    n = len(normals)
    qm = [[sum(1.5 * v[i] * v[j] - (0.5 if i == j else 0.0) for v in normals) / n
           for j in range(3)] for i in range(3)]
    polar = math.sqrt(sum((sum(v[a] for v in normals) / n) ** 2 for a in range(3)))
    return largest_eig_sym3(qm), polar


def mean_nearest(centres, box, periodic):
    total = 0.0
    for i, ci in enumerate(centres):
        best = float("inf")
        for j, cj in enumerate(centres):
            if i != j:
                d = wrap([ci[a] - cj[a] for a in range(3)], box, periodic)
                best = min(best, math.sqrt(sum(x * x for x in d)))
        total += best
    return total / len(centres)


def analyse(frame):
    step, box, periodic, mols = frame
    pl = platelets(box, periodic, mols)
    s, polar = order([n for _, n in pl])
    return step, s, polar, mean_nearest([c for c, _ in pl], box, periodic), len(pl)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--thickness", type=float, default=0.026)
    ap.add_argument("--min-order", type=float, default=0.9)
    ap.add_argument("--max-spacing-factor", type=float, default=1.5)
    ap.add_argument("--max-shrink", type=float, default=0.6)
    a = ap.parse_args()
    frames = read_frames(os.path.join(a.outdir, "pebbles.dump"))
    first, last = analyse(frames[0]), analyse(frames[-1])
    for tag, (step, s, polar, nn, count) in (("first", first), ("last", last)):
        print(f"{tag} frame (step {step}, {count} platelets): order parameter S = {s:.4f}, "
              f"polar order = {polar:.4f}, mean nearest-platelet distance = {nn:.4f}")
    ok = True
    if not last[1] > a.min_order:
        print(f"FAIL: order parameter {last[1]:.4f} <= {a.min_order}")
        ok = False
    limit = a.max_spacing_factor * a.thickness
    if not last[3] < limit:
        print(f"FAIL: mean nearest-platelet distance {last[3]:.4f} >= {limit:.4f} (not near contact)")
        ok = False
    if not last[3] < a.max_shrink * first[3]:
        print(f"FAIL: mean nearest-platelet distance shrank only from {first[3]:.4f} to {last[3]:.4f}")
        ok = False
    print("PASS" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
