#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Plot the platelets energies from out/energy.dat (written by in.platelets).

Normalized as the source paper does: t_hat = t / T_max and U_hat = U / U_ref with
U_ref = |U_LR(T_max)|. Panels: (B) U_LR / U_ref; (C) U_tra, U_rot, U_kin and U_ela over U_ref;
and the nematic order parameter of the platelet normals with the mean nearest-platelet
distance, from the frames of out/pebbles.dump (the same analysis as the ctest checker,
unittest/examples/check_platelets.py, whose functions are used when it is found).
Writes out/energy.png and out/structure.dat (step, order parameter, polar order, mean
nearest-platelet distance).

usage: python3 plot_energy.py [OUTDIR]
"""
import importlib
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "common"))
sys.path.insert(0, os.path.join(HERE, "..", "..", "unittest", "examples"))
import kifmm_plots as kp  # noqa: E402

try:
    checker = importlib.import_module("check_platelets")
except ImportError:
    checker = None


def main(directory="out"):
    e = kp.Energy(directory, uref="last")
    fig, axes = kp.figure(3, (13, 3.6))
    kp.plot_ulr(axes[0], e, ylabel=r"$\hat U = U / |U_{LR}(1)|$")
    ax = axes[1]
    for name, label in (("U_tra", r"$U_{tra}$"), ("U_rot", r"$U_{rot}$"),
                        ("U_kin", r"$U_{kin}$"), ("U_ela", r"$U_{ela}$")):
        ax.plot(e.th, [u / e.uref for u in e.column(name)], label=label)
    ax.set_ylabel(r"$\hat U$")
    ax.legend()
    ax = axes[2]
    t = e.t
    dump = os.path.join(directory, "pebbles.dump")
    if checker is not None and os.path.exists(dump):
        frames = checker.read_frames(dump)
        dt = t[-1] / frames[-1][0] if frames[-1][0] else 1.0
        res = [checker.analyse(fr) for fr in frames]
        with open(os.path.join(directory, "structure.dat"), "w") as f:
            f.write("# step order_parameter polar_order mean_nearest_platelet_distance\n")
            for step, s, polar, nn, _ in res:
                f.write(f"{step} {s:.6f} {polar:.6f} {nn:.6f}\n")
        tt = [step * dt / t[-1] for step, *_ in res]
        ax.plot(tt, [r[1] for r in res], "o-", label="order parameter S")
        ax.set_ylabel("order parameter S")
        ax.set_ylim(0, 1.02)
        ax2 = ax.twinx()
        ax2.plot(tt, [r[3] for r in res], "s-", color="C1", label="mean nearest distance")
        ax2.set_ylabel("mean nearest-platelet distance")
        ax.legend(loc="lower left")
        ax2.legend(loc="upper right")
    for ax in axes:
        ax.set_xlabel(kp.T_HAT)
    kp.save(fig, directory, dpi=90)


if __name__ == "__main__":
    main(*sys.argv[1:])
