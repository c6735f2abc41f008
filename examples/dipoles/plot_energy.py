#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Plot the dipoles energies from out/energy.dat (written by in.dipoles).

Normalized as the source paper does: t_hat = t / T_max and U_hat = U / U_ref with
U_ref = |U_LR(T_max)|. Panels: (B) U_LR / U_ref; (C) U_gra, U_ela and U_kin over U_ref
(U_gra relative to its initial value, as only its change matters); and the size of the
largest aggregate (clumps connected through pebble contacts, pebble centres of different
clumps closer than 2.04 r, from the frames of out/clumps.dump) with the centre-of-mass height.
Writes out/energy.png and out/aggregates.dat (step, largest aggregate, number of aggregates).

usage: python3 plot_energy.py [OUTDIR]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import kifmm_plots as kp  # noqa: E402


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
            for line in lines[k + 9:k + 9 + n]:
                p = line.split()
                pebbles.append((int(p[im]), float(p[ix]), float(p[iy]), float(p[iz])))
            frames.append((step, pebbles))
            k += 9 + n
        else:
            k += 1
    return frames


def aggregates(pebbles, cut):
    """Sizes (in clumps) of the sets of clumps connected by pebble contacts."""
    parent = {m: m for m, *_ in pebbles}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    cells = {}
    for k, (m, x, y, z) in enumerate(pebbles):
        cells.setdefault((int(x // cut), int(y // cut), int(z // cut)), []).append(k)
    cut2 = cut * cut
    for (cx, cy, cz), members in cells.items():
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for j in cells.get((cx + dx, cy + dy, cz + dz), ()):
                        mj, xj, yj, zj = pebbles[j]
                        for i in members:
                            mi, xi, yi, zi = pebbles[i]
                            if mi == mj or (xi - xj) ** 2 + (yi - yj) ** 2 + (zi - zj) ** 2 >= cut2:
                                continue
                            a, b = find(mi), find(mj)
                            if a != b:
                                parent[a] = b
    sizes = {}
    for m in parent:
        r = find(m)
        sizes[r] = sizes.get(r, 0) + 1
    return sorted(sizes.values(), reverse=True)


def main(directory="out"):
    e = kp.Energy(directory, uref="last")
    fig, axes = kp.figure(3, (13, 3.6))
    kp.plot_ulr(axes[0], e, ylabel=r"$\hat U = U / |U_{LR}(1)|$")
    ax = axes[1]
    uref = e.uref
    g0 = e.column("U_gra")[0]
    ax.plot(e.th, [(u - g0) / uref for u in e.column("U_gra")], label=r"$U_{gra} - U_{gra}(0)$")
    ax.plot(e.th, [u / uref for u in e.column("U_ela")], label=r"$U_{ela}$")
    ax.plot(e.th, [u / uref for u in e.column("U_kin")], label=r"$U_{kin}$")
    ax.set_ylabel(r"$\hat U$")
    ax.legend()
    ax = axes[2]
    frames = read_frames(os.path.join(directory, "clumps.dump"))
    radius = float(os.environ.get("PEBBLE_RADIUS", "0.005"))
    t = e.t
    dt = t[-1] / frames[-1][0] if frames[-1][0] else 1.0
    series = []
    with open(os.path.join(directory, "aggregates.dat"), "w") as f:
        f.write("# step largest_aggregate_clumps number_of_aggregates\n")
        for step, pebbles in frames:
            sizes = aggregates(pebbles, 2.04 * radius)
            series.append((step, sizes[0]))
            f.write(f"{step} {sizes[0]} {len(sizes)}\n")
    ax.plot([s * dt / t[-1] for s, _ in series], [n for _, n in series], "o-", label="largest aggregate")
    ax.set_ylabel("largest aggregate (clumps)")
    ax2 = ax.twinx()
    ax2.plot(e.th, e.column("zcm/L"), color="C1", label="centre of mass z / L")
    ax2.set_ylabel("centre of mass z / L")
    ax.legend(loc="upper left")
    ax2.legend(loc="center right")
    for ax in axes:
        ax.set_xlabel(kp.T_HAT)
    kp.save(fig, directory, dpi=90)


if __name__ == "__main__":
    main(*sys.argv[1:])
