#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Plot the charges-box energies from out/energy.dat (written by in.charges-box).

Normalized as the source paper does: t_hat = t / T_max and U_hat = U / U_ref with
U_ref = U_LR(0). Left: U_LR / U_LR(0) (the paper's figure 1B). Right: the fraction of spheres
whose centre is within 2r of a wall. Writes out/energy.png.

usage: python3 plot_energy.py [OUTDIR]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import kifmm_plots as kp  # noqa: E402


def main(directory="out"):
    e = kp.Energy(directory, uref="first_signed")
    fig, axes = kp.figure(2, (9, 3.5))
    kp.plot_ulr(axes[0], e, label=r"$U_{LR}/U_{LR}(0)$", ylabel=r"$\hat U$")
    ax = axes[1]
    if len(e.rows[0]) > 3:
        ax.plot(e.th, [r[3] for r in e.rows], color="C1")
        ax.axhline(0.9, color="grey", lw=0.8, ls="--")
    ax.set_ylabel("fraction within 2r of a wall")
    ax.set_ylim(0, 1.02)
    for ax in axes:
        ax.set_xlabel(kp.T_HAT)
    kp.save(fig, directory, dpi=100)


if __name__ == "__main__":
    main(*sys.argv[1:])
