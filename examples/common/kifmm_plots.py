# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Shared part of the example scenes' plot_energy.py scripts: matplotlib set-up, reading of
out/energy.dat, the figure with the paper's normalization (t_hat = t / T_max, U_hat = U /
U_ref) and its long-range energy panel, and saving out/energy.png.

Each examples/<scene>/plot_energy.py imports this module (from ../common) and adds its
scene's panels.
"""
import os
import sys

T_HAT = r"$\hat t = t / T_{max}$"


def pyplot():
    """matplotlib.pyplot with the Agg backend. If the running python3 lacks matplotlib (e.g. a
    pyenv python3 first in PATH), the script is run again with Debian's /usr/bin/python3."""
    try:
        import matplotlib
    except ImportError:
        if os.path.exists("/usr/bin/python3") and sys.executable != "/usr/bin/python3":
            os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
        raise
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def read_table(path):
    """(column names, rows of floats) of an energy.dat written by fix print: the column names
    come from its first line ("# time U_LR ..."); a row whose time repeats the previous one
    (fix print at the start of each run) is dropped."""
    head, rows = [], []
    with open(path) as f:
        for k, line in enumerate(f):
            if k == 0 and line.startswith("#"):
                head = line.split()[1:]
                continue
            if line.startswith("#") or not line.strip():
                continue
            row = [float(v) for v in line.split()]
            if rows and row[0] == rows[-1][0]:
                continue
            rows.append(row)
    return head, rows


class Energy:
    """The rows of out/energy.dat with t_hat and U_ref.

    tmax: T_max for t_hat (default: the last time in the file); uref: "first" (|U_LR(0)|),
    "last" (|U_LR(T_max)|) or "first_signed" (U_LR(0) with its sign)."""

    def __init__(self, directory, tmax=None, uref="last"):
        self.head, self.rows = read_table(os.path.join(directory, "energy.dat"))
        self.col = {name: k for k, name in enumerate(self.head)}
        self.t = [r[0] for r in self.rows]
        self.tmax = float(tmax) if tmax else (self.t[-1] if self.t[-1] > 0 else 1.0)
        self.th = [ti / self.tmax for ti in self.t]
        ulr = self.column("U_LR")
        self.uref = {"first": abs(ulr[0]), "last": abs(ulr[-1]), "first_signed": ulr[0]}[uref]

    def column(self, name):
        return [r[self.col[name]] for r in self.rows]


def figure(ncols, figsize):
    """A figure with ncols panels side by side: (fig, axes)."""
    plt = pyplot()
    fig, axes = plt.subplots(1, ncols, figsize=figsize)
    return fig, axes


def plot_ulr(ax, energy, label=r"$U_{LR}$", ylabel=None):
    """The paper's panel B: U_LR / U_ref against t_hat."""
    ax.plot(energy.th, [u / energy.uref for u in energy.column("U_LR")], label=label)
    if ylabel:
        ax.set_ylabel(ylabel)
    ax.legend()


def save(fig, directory, dpi):
    """Writes DIRECTORY/energy.png and says so."""
    fig.tight_layout()
    out = os.path.join(directory, "energy.png")
    fig.savefig(out, dpi=dpi)
    print("wrote", out)
