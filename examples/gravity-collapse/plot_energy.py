#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Plot the gravity-collapse energies from out/energy.dat (written by in.gravity-collapse).

Normalized as the source paper does: t_hat = t / T_max, U_hat = U / U_ref. The paper does not
state U_ref for this scene; here U_ref = |U_LR(0)|, the gravitational energy of the initial
cloud. Panels: (B) U_LR / U_ref, (C) U_kin / U_ref and U_ela / U_ref (log scale), and the
radius of gyration with the axis ratio of the gyration tensor. Writes out/energy.png.

usage: python3 plot_energy.py [OUTDIR] [TMAX]

TMAX (default: the last time in energy.dat) normalizes t; give 5 for a run stopped early.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import kifmm_plots as kp  # noqa: E402


def main(directory="out", tmax=None):
    e = kp.Energy(directory, tmax=tmax, uref="first")
    fig, axes = kp.figure(3, (13, 3.6))
    kp.plot_ulr(axes[0], e, ylabel=r"$\hat U = U / |U_{LR}(0)|$")
    ax = axes[1]
    ax.semilogy(e.th, [max(u, 1e-30) / e.uref for u in e.column("U_kin")], label=r"$U_{kin}$")
    ax.semilogy(e.th, [max(u, 1e-30) / e.uref for u in e.column("U_ela")], label=r"$U_{ela}$")
    ax.set_ylabel(r"$\hat U$")
    ax.set_ylim(bottom=1e-6)
    ax.legend()
    ax = axes[2]
    ax.plot(e.th, e.column("Rg"), label=r"$R_g$")
    ax.set_ylabel(r"$R_g$")
    ax2 = ax.twinx()
    ax2.plot(e.th, e.column("axis_ratio"), color="C1", label="axis ratio")
    ax2.set_ylabel("axis ratio (shortest / longest)")
    ax2.set_ylim(0, 1.02)
    ax.legend(loc="upper center")
    ax2.legend(loc="center right")
    for ax in axes:
        ax.set_xlabel(kp.T_HAT)
    kp.save(fig, directory, dpi=90)


if __name__ == "__main__":
    main(*sys.argv[1:])
