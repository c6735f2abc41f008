#!/usr/bin/env python3
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

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "unittest", "examples"))
try:
    import importlib
    checker = importlib.import_module("check_platelets")
except ImportError:
    checker = None


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


def main(directory="out"):
    head, rows = read_table(os.path.join(directory, "energy.dat"))
    col = {name: k for k, name in enumerate(head)}
    t = [r[0] for r in rows]
    th = [ti / t[-1] for ti in t]
    uref = abs(rows[-1][col["U_LR"]])
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    ax = axes[0]
    ax.plot(th, [r[col["U_LR"]] / uref for r in rows], label=r"$U_{LR}$")
    ax.set_ylabel(r"$\hat U = U / |U_{LR}(1)|$")
    ax.legend()
    ax = axes[1]
    for name, label in (("U_tra", r"$U_{tra}$"), ("U_rot", r"$U_{rot}$"),
                        ("U_kin", r"$U_{kin}$"), ("U_ela", r"$U_{ela}$")):
        ax.plot(th, [r[col[name]] / uref for r in rows], label=label)
    ax.set_ylabel(r"$\hat U$")
    ax.legend()
    ax = axes[2]
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
        ax.set_xlabel(r"$\hat t = t / T_{max}$")
    fig.tight_layout()
    out = os.path.join(directory, "energy.png")
    fig.savefig(out, dpi=90)
    print("wrote", out)


if __name__ == "__main__":
    main(*sys.argv[1:])
