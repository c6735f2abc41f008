#!/usr/bin/env python3
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

try:
    import matplotlib
except ImportError:  # e.g. a pyenv python3 first in PATH: use Debian's, which has matplotlib
    if os.path.exists("/usr/bin/python3") and sys.executable != "/usr/bin/python3":
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    raise
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_table(path):
    """Column names and rows; a row repeating the previous time (fix print at the start of
    each run) is dropped."""
    rows = []
    with open(path) as f:
        head = f.readline().split()[1:]
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            row = [float(v) for v in line.split()]
            if rows and row[0] == rows[-1][0]:
                continue
            rows.append(row)
    return head, rows


def main(directory="out", tmax=None):
    head, rows = read_table(os.path.join(directory, "energy.dat"))
    col = {name: k for k, name in enumerate(head)}
    t = [r[0] for r in rows]
    tmax = float(tmax) if tmax else t[-1]
    th = [ti / tmax for ti in t]
    uref = abs(rows[0][col["U_LR"]])
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    ax = axes[0]
    ax.plot(th, [r[col["U_LR"]] / uref for r in rows], label=r"$U_{LR}$")
    ax.set_ylabel(r"$\hat U = U / |U_{LR}(0)|$")
    ax.legend()
    ax = axes[1]
    ax.semilogy(th, [max(r[col["U_kin"]], 1e-30) / uref for r in rows], label=r"$U_{kin}$")
    ax.semilogy(th, [max(r[col["U_ela"]], 1e-30) / uref for r in rows], label=r"$U_{ela}$")
    ax.set_ylabel(r"$\hat U$")
    ax.set_ylim(bottom=1e-6)
    ax.legend()
    ax = axes[2]
    ax.plot(th, [r[col["Rg"]] for r in rows], label=r"$R_g$")
    ax.set_ylabel(r"$R_g$")
    ax2 = ax.twinx()
    ax2.plot(th, [r[col["axis_ratio"]] for r in rows], color="C1", label="axis ratio")
    ax2.set_ylabel("axis ratio (shortest / longest)")
    ax2.set_ylim(0, 1.02)
    ax.legend(loc="upper center")
    ax2.legend(loc="center right")
    for ax in axes:
        ax.set_xlabel(r"$\hat t = t / T_{max}$")
    fig.tight_layout()
    out = os.path.join(directory, "energy.png")
    fig.savefig(out, dpi=90)
    print("wrote", out)


if __name__ == "__main__":
    main(*sys.argv[1:])
