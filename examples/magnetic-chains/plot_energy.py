#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Plot the magnetic-chains energies and structures from out/ (written by in.magnetic-chains).

t_hat = t / T_max. Left: the dipole energy U_LR, the gravitational energy U_gra and the kinetic
energy (translation and rotation) over |U_LR(T_max)|. Right: the fraction of spheres in
chains and in rings, and the head-to-tail alignment of the contacts (structures.py, written to
out/structures.dat). Writes out/energy.png.

usage: python3 plot_energy.py [OUTDIR]
"""
import os
import sys

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "common"))
sys.path.insert(0, here)
import kifmm_plots as kp  # noqa: E402
import structures  # noqa: E402


def main(directory="out"):
    e = kp.Energy(directory, uref="last")
    rows = structures.table(directory)
    with open(os.path.join(directory, "structures.dat"), "w") as f:
        f.write("# time in_chains in_rings chains rings head_to_tail z_mean\n")
        for r in rows:
            f.write(" ".join(f"{v:.6g}" for v in r) + "\n")
    fig, axes = kp.figure(2, (10, 3.8))
    ax = axes[0]
    kp.plot_ulr(ax, e, label=r"$U_{LR}$")
    ax.plot(e.th, [u / e.uref for u in e.column("U_gra")], label=r"$U_{gra}$")
    ax.plot(e.th, [u / e.uref for u in e.column("U_kin")], label=r"$U_{kin}$")
    ax.set_ylabel(r"$U / |U_{LR}(T_{max})|$")
    ax.legend(fontsize=8)
    ax = axes[1]
    th = [r[0] / e.tmax for r in rows]
    ax.plot(th, [r[1] for r in rows], label="in chains")
    ax.plot(th, [r[2] for r in rows], label="in rings")
    ax.plot(th, [r[5] for r in rows], label="head-to-tail alignment")
    ax.set_ylim(0, 1.02)
    ax.set_ylabel("fraction of spheres / alignment")
    ax.legend(fontsize=8, loc="center right")
    for a in axes:
        a.set_xlabel(kp.T_HAT)
    kp.save(fig, directory, dpi=100)


if __name__ == "__main__":
    main(*sys.argv[1:])
