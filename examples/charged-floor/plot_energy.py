#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Plot the charged-floor energies from out/energy.dat (written by in.charged-floor).

t_hat = t / T_max. Left: U_LR / |U_LR(0)| and U_kin / |U_LR(0)|. Right: the fraction of spheres
on the floor (centre below 1.5 r) and the height of the highest sphere. Writes out/energy.png.

usage: python3 plot_energy.py [OUTDIR]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import kifmm_plots as kp  # noqa: E402


def main(directory="out"):
    e = kp.Energy(directory, uref="first")
    fig, axes = kp.figure(2, (9, 3.5))
    kp.plot_ulr(axes[0], e, label=r"$U_{LR}/|U_{LR}(0)|$", ylabel=r"$\hat U$")
    axes[0].plot(e.th, [u / e.uref for u in e.column("U_kin")], label=r"$U_{kin}/|U_{LR}(0)|$")
    axes[0].legend()
    ax = axes[1]
    ax.plot(e.th, e.column("fraction_on_floor"), color="C1", label="fraction on the floor")
    ax.set_ylim(0, 1.02)
    ax2 = ax.twinx()
    ax2.plot(e.th, e.column("z_max"), color="C2", label="highest sphere z")
    ax2.set_ylabel("highest sphere z")
    ax.set_ylabel("fraction on the floor")
    ax.legend(loc="center right")
    for a in axes:
        a.set_xlabel(kp.T_HAT)
    kp.save(fig, directory, dpi=100)


if __name__ == "__main__":
    main(*sys.argv[1:])
