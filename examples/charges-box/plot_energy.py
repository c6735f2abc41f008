#!/usr/bin/env python3
"""Plot U_LR / U_LR(0) against t/T_max from out/energy.dat (written by in.charges-box)."""
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(directory="out"):
    rows = []
    with open(os.path.join(directory, "energy.dat")) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            rows.append([float(v) for v in line.split()])
    t = [r[0] for r in rows]
    tmax = t[-1] if t[-1] > 0 else 1.0
    u0 = rows[0][1]
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot([ti / tmax for ti in t], [r[1] / u0 for r in rows], label=r"$U_{LR}/U_{LR}(0)$")
    ax.set_xlabel(r"$\hat t = t / T_{max}$")
    ax.set_ylabel(r"$\hat U$")
    ax.legend()
    fig.tight_layout()
    out = os.path.join(directory, "energy.png")
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main(*sys.argv[1:])
