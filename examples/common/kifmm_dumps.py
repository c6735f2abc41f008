# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Shared part of the example scenes' analysis scripts: the frames of a LAMMPS text dump
(dump custom: ITEM: TIMESTEP / NUMBER OF ATOMS / BOX BOUNDS / ATOMS <columns>)."""


def frames(path, columns):
    """Yields (step, box edge lengths, rows) for every frame of the dump at `path`; each row
    holds the values of `columns` (names of the dump's columns, e.g. ("x", "y", "z"))."""
    with open(path) as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines):
        if not lines[i].startswith("ITEM: TIMESTEP"):
            i += 1
            continue
        step = int(lines[i + 1])
        n = int(lines[i + 3])
        box = [[float(v) for v in lines[i + 5 + k].split()[:2]] for k in range(3)]
        names = lines[i + 8].split()[2:]
        idx = [names.index(c) for c in columns]
        rows = []
        for line in lines[i + 9:i + 9 + n]:
            v = line.split()
            rows.append([float(v[k]) for k in idx])
        yield step, [b[1] - b[0] for b in box], rows
        i += 9 + n
