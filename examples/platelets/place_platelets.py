#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Random, non-overlapping, co-oriented placement of platelets; writes LAMMPS commands.

Each platelet is a hexagonal two-layer clump whose normal is z (as in the molecule file); all
keep the orientation of the file (co-oriented: same normal and same in-plane orientation).
Two platelets are taken to overlap when their centres are closer than `thickness` in z and
closer than 2 * `radius` in the xy plane (radius = circumradius of the hexagon + pebble
radius, so the test is conservative). Centres are drawn uniformly in the box (periodic:
minimum-image distances; walls: the platelet stays inside the box) by random sequential
addition.

usage: place_platelets.py --count 50 --box 1.0 --radius 0.1405 --thickness 0.0242
                          [--periodic] --seed 2024 --mol platelet -o positions.lmp
"""
import argparse
import random
import sys


def place(count, box, radius, thickness, periodic, seed, tries=100000):
    rng = random.Random(seed)
    centres = []
    if periodic:
        lo_xy, hi_xy, lo_z, hi_z = 0.0, box, 0.0, box
    else:
        lo_xy, hi_xy = radius, box - radius
        lo_z, hi_z = thickness / 2, box - thickness / 2
        if lo_xy >= hi_xy or lo_z >= hi_z:
            raise ValueError("box too small for one platelet")

    def d(a, b):
        x = a - b
        if periodic:
            x -= box * round(x / box)
        return x

    for _ in range(count):
        for _ in range(tries):
            c = (rng.uniform(lo_xy, hi_xy), rng.uniform(lo_xy, hi_xy), rng.uniform(lo_z, hi_z))
            if all(abs(d(c[2], o[2])) >= thickness or
                   d(c[0], o[0]) ** 2 + d(c[1], o[1]) ** 2 >= (2 * radius) ** 2
                   for o in centres):
                centres.append(c)
                break
        else:
            raise RuntimeError(f"placed only {len(centres)} of {count} platelets")
    return centres


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--count", type=int, required=True)
    ap.add_argument("--box", type=float, required=True)
    ap.add_argument("--radius", type=float, required=True)
    ap.add_argument("--thickness", type=float, required=True)
    ap.add_argument("--periodic", action="store_true")
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--mol", default="platelet")
    ap.add_argument("-o", "--output", default="-")
    a = ap.parse_args()
    centres = place(a.count, a.box, a.radius, a.thickness, a.periodic, a.seed)
    lines = [f"# {a.count} co-oriented platelets, box {a.box}, "
             f"{'periodic' if a.periodic else 'walls'}, seed {a.seed}; "
             f"written by place_platelets.py"]
    for k, (x, y, z) in enumerate(centres):
        lines.append(f"create_atoms 0 single {x:.6f} {y:.6f} {z:.6f} mol {a.mol} {a.seed + k} "
                     f"rotate 0 0 0 1 units box")
    text = "\n".join(lines) + "\n"
    if a.output == "-":
        sys.stdout.write(text)
    else:
        with open(a.output, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
