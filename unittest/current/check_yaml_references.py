#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""The package's force-style references (force-styles/kspace-kifmm_*_open.yaml, generated with
LAMMPS's test_pair_style) against an exact direct sum of the same physics over data.kifmm:
coulomb q_i q_j / r, gravity -G m_i m_j / r, yukawa q_i q_j exp(-kappa r) / r (lj units,
qqrd2e = 1). The references hold kifmm forces at order 8: equal to 1e-6 relative RMS.

usage: check_yaml_references.py FORCE_STYLES_DIR"""
import math
import os
import re
import sys


def read_data(path):
    masses, atoms, section = {}, [], None
    for line in open(path):
        line = line.split("#")[0].strip()
        if not line:
            continue
        if line in ("Masses", "Atoms"):
            section = line
            continue
        v = line.split()
        if section == "Masses" and len(v) == 2:
            masses[int(v[0])] = float(v[1])
        elif section == "Atoms" and len(v) >= 6:
            atoms.append((int(v[0]), int(v[1]), float(v[2]), [float(x) for x in v[3:6]]))
    return masses, atoms


def read_forces(path, key):
    text = open(path).read()
    m = re.search(key + r": \|2\n((?:\s+\d+\s+\S+\s+\S+\s+\S+\n)+)", text)
    if not m:
        sys.exit(f"{path}: no {key}")
    out = {}
    for line in m.group(1).splitlines():
        v = line.split()
        out[int(v[0])] = [float(x) for x in v[1:4]]
    return out


def direct(atoms, strength, pair):
    f = {a[0]: [0.0, 0.0, 0.0] for a in atoms}
    for i, a in enumerate(atoms):
        for b in atoms[i + 1:]:
            d = [a[3][k] - b[3][k] for k in range(3)]
            r = math.sqrt(sum(x * x for x in d))
            mag = pair(r) * strength(a) * strength(b)    # -dU/dr for the product of strengths
            for k in range(3):
                f[a[0]][k] += mag * d[k] / r
                f[b[0]][k] -= mag * d[k] / r
    return f


def main(folder):
    masses, atoms = read_data(os.path.join(folder, "data.kifmm"))
    kappa = 1.5
    cases = {
        "kspace-kifmm_coulomb_open.yaml": (lambda a: a[2], lambda r: 1.0 / r ** 2),
        "kspace-kifmm_gravity_open.yaml": (lambda a: masses[a[1]], lambda r: -0.5 / r ** 2),
        "kspace-kifmm_yukawa_open.yaml": (lambda a: a[2],
                                          lambda r: math.exp(-kappa * r) * (1.0 / r ** 2 + kappa / r)),
    }
    worst = 0.0
    for name, (strength, pair) in cases.items():
        ref = read_forces(os.path.join(folder, name), "init_forces")
        exact = direct(atoms, strength, pair)
        num = sum((ref[i][k] - exact[i][k]) ** 2 for i in exact for k in range(3))
        den = sum(exact[i][k] ** 2 for i in exact for k in range(3))
        err = math.sqrt(num / den)
        print(f"{name}: relative RMS difference from the direct sum {err:.2e}")
        worst = max(worst, err)
    if worst > 1e-6:
        sys.exit("a reference differs from the exact sum")
    print("OK")


if __name__ == "__main__":
    main(sys.argv[1])
