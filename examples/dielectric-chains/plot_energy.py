#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Plot the dielectric-chains energies and chains from out/ (written by in.dielectric-chains).

t_hat = t / T_max. Left: the long-range energy of the dipoles U_LR, the polarization energy
U_pol, the energy in the external field U_field and their sum with the kinetic energy (which
the drag and the contact damping can only lower), all over |U_total(0)|. Right: the fraction
of spheres in field-aligned chains, the contact order p2 and the fraction in chains that span
the electrode gap (chains.py, written to out/chains.dat). Writes out/energy.png.

usage: python3 plot_energy.py [OUTDIR]
"""
import os
import sys

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "common"))
sys.path.insert(0, here)
import chains  # noqa: E402
import kifmm_plots as kp  # noqa: E402


def main(directory="out"):
    e = kp.Energy(directory, uref="first")
    ulr, upol, ufield, ukin = (e.column(c) for c in ("U_LR", "U_pol", "U_field", "U_kin"))
    total = [a + b + c + d for a, b, c, d in zip(ulr, upol, ufield, ukin)]
    ref = abs(total[0])
    rows = chains.table(directory)
    with open(os.path.join(directory, "chains.dat"), "w") as f:
        f.write("# time aligned p2 spanning\n")
        for r in rows:
            f.write(" ".join(f"{v:.6g}" for v in r) + "\n")
    fig, axes = kp.figure(2, (10, 3.8))
    ax = axes[0]
    for values, label in ((ulr, r"$U_{LR}$"), (upol, r"$U_{pol}$"), (ufield, r"$U_{field}$"),
                          (total, r"$U_{LR} + U_{pol} + U_{field} + U_{kin}$")):
        ax.plot(e.th, [u / ref for u in values], label=label)
    ax.set_ylabel(r"$U / |U_{total}(0)|$")
    ax.legend(fontsize=8)
    ax = axes[1]
    th = [r[0] / e.tmax for r in rows]
    ax.plot(th, [r[1] for r in rows], label="in field-aligned chains")
    ax.plot(th, [r[2] for r in rows], label=r"contact order $p_2$")
    ax.plot(th, [r[3] for r in rows], label="in chains spanning the gap")
    ax.set_ylim(0, 1.02)
    ax.set_ylabel("fraction of spheres / order")
    ax.legend(fontsize=8, loc="lower right")
    for a in axes:
        a.set_xlabel(kp.T_HAT)
    kp.save(fig, directory, dpi=100)


if __name__ == "__main__":
    main(*sys.argv[1:])
