#!/usr/bin/env python3
"""Plot the charges-box energies from out/energy.dat (written by in.charges-box).

Normalized as the source paper does: t_hat = t / T_max and U_hat = U / U_ref with
U_ref = U_LR(0). Left: U_LR / U_LR(0) (the paper's figure). Right: the fraction of spheres
whose centre is within 2r of a wall. Writes out/energy.png.

usage: python3 plot_energy.py [OUTDIR]
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
    """Rows of floats; a row whose time repeats the previous one (fix print at the start of
    each run) is dropped."""
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            row = [float(v) for v in line.split()]
            if rows and row[0] == rows[-1][0]:
                continue
            rows.append(row)
    return rows


def main(directory="out"):
    rows = read_table(os.path.join(directory, "energy.dat"))
    t = [r[0] for r in rows]
    tmax = t[-1] if t[-1] > 0 else 1.0
    th = [ti / tmax for ti in t]
    u0 = rows[0][1]
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
    ax = axes[0]
    ax.plot(th, [r[1] / u0 for r in rows], label=r"$U_{LR}/U_{LR}(0)$")
    ax.set_xlabel(r"$\hat t = t / T_{max}$")
    ax.set_ylabel(r"$\hat U$")
    ax.legend()
    ax = axes[1]
    if len(rows[0]) > 3:
        ax.plot(th, [r[3] for r in rows], color="C1")
        ax.axhline(0.9, color="grey", lw=0.8, ls="--")
    ax.set_xlabel(r"$\hat t = t / T_{max}$")
    ax.set_ylabel("fraction within 2r of a wall")
    ax.set_ylim(0, 1.02)
    fig.tight_layout()
    out = os.path.join(directory, "energy.png")
    fig.savefig(out, dpi=100)
    print("wrote", out)


if __name__ == "__main__":
    main(*sys.argv[1:])
