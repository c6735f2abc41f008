#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Report: tables (markdown) and plots (PNG) from the results of run_bench.py.

Matched-error times: each solver's runs on one case and N form its Pareto front (runs not
beaten in both time and error by another run of the same solver); the time at error E is
interpolated linearly in log(time)-log(error) between the two front points around E. If even
the fastest run is more accurate than E, its time is used (an upper bound, marked <=); if no
run reaches E the solver has no time at E (n/r). Direct summation is exact: its time holds at
every E; above the N where it was run it is extrapolated as N^2 (marked ~; open boundaries
only).
"""

import argparse
import json
import math
import os
import re
import sys
import textwrap

TARGETS = (1e-3, 1e-5, 1e-7)
EXACT = ("direct", "coulcut")
COLORS = {"kifmm": "tab:blue", "msm": "tab:orange", "direct": "tab:green",
          "coulcut": "tab:olive", "ewald": "tab:red", "pppm": "tab:purple"}
LABELS = {"kifmm": "kifmm", "msm": "msm (pair coul/msm + kspace msm)",
          "direct": "direct sum (kifmm::direct_sum)", "coulcut": "direct sum (LAMMPS coul/cut)",
          "ewald": "ewald", "pppm": "pppm"}


# archived kifmm runs of earlier engine commits (results/kifmm-COMMIT.jsonl), newest first;
# any other kifmm-*.jsonl next to the results file is listed after these
ARCHIVES = ("kifmm-2c78d4f.jsonl", "kifmm-c4d85d4.jsonl", "kifmm-923c304.jsonl", "kifmm-cbcfc98.jsonl")

SKIPPED_WALL = []    # (case, n, spec) of runs without CPU times (left out: see load)


def load(path):
    recs = {}
    if not os.path.exists(path):
        return []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            try:
                r = json.loads(line)
            except json.JSONDecodeError:
                continue
            # a single isolated body (one platelet) has a zero net force (third law): its
            # relative net-force error would be relative to round-off, so it is not reported
            if r.get("clump_error") is not None and r.get("f_rms") and \
                    r.get("clump_f_rms", 0) < 1e-6 * r["f_rms"]:
                r["clump_error"] = None
            # cost = CPU time of the process per evaluation (c_*) where measured: insensitive to
            # the other processes on the shared cores; the wall times stay as t_wall_*
            # the same for the setup (c_setup). A run with wall times only (an older binary)
            # is left out: its times must not enter a ratio with CPU times
            if "c_eval" in r:
                for k in ("eval", "pair", "kspace", "setup"):
                    if f"c_{k}" in r:
                        r[f"t_wall_{k}"] = r.get(f"t_{k}")
                        r[f"t_{k}"] = r[f"c_{k}"]
            elif r.get("kind") == "run" and r.get("status") == "ok":
                SKIPPED_WALL.append((r.get("case"), r.get("n"), r.get("spec")))
                continue
            recs[(r.get("kind"), r.get("case"), r.get("n"), r.get("spec"))] = r    # latest wins
    for r in recs.values():
        if r.get("kind") == "reference" and r.get("f_rms_all"):
            F_RMS_ALL[(r["case"], r["n"])] = (r["f_rms"], r["f_rms_all"])
    for r in recs.values():
        all_atom_error(r)
    return list(recs.values())


# (case, n) -> (RMS force of the sample, RMS force of all atoms) of the sampled references
F_RMS_ALL = {}


def all_atom_error(r):
    """A run on a sampled reference recorded before the references held the RMS force of all
    atoms: its error (the sample's own ratio) in the measure of the later runs, the sample's
    mean squared error over the mean squared force of all atoms, which is the recorded error
    times (RMS force of the sample) / (RMS force of all atoms) when the sample is the same
    (the same RMS force of the sample); the sample's ratio stays as error_sample."""
    if r.get("kind") != "run" or r.get("error") is None or "error_denominator" in r:
        return
    ref = F_RMS_ALL.get((r.get("case"), r.get("n")))
    if ref is None or not r.get("f_rms") or abs(r["f_rms"] - ref[0]) > 1e-5 * ref[0]:
        return
    r["error_sample"] = r["error"]
    r["error"] = r["error"] * r["f_rms"] / ref[1]
    r["error_denominator"] = "all atoms (rescaled)"


def ok_runs(recs, case=None, n=None, solver=None):
    out = []
    for r in recs:
        if r.get("kind") != "run" or r.get("status") != "ok":
            continue
        if case is not None and r["case"] != case:
            continue
        if n is not None and r["n"] != n:
            continue
        if solver is not None and r["solver"] != solver:
            continue
        if not (r.get("error", -1) >= 0 and math.isfinite(r["error"])):
            continue
        out.append(r)
    return out


def front(runs, key="error"):
    pts = sorted(runs, key=lambda r: (r["t_eval"], r[key]))
    out, best = [], float("inf")
    for r in pts:
        if r[key] < best:
            out.append(r)
            best = r[key]
    return out


COMPETITORS = ("msm", "ewald", "pppm")


def is_periodic(recs, case):
    return any(r.get("periodic") for r in recs if r.get("case") == case)


def competitors(recs, cases):
    """Approximate competitors (msm, ewald, pppm) with runs in any of the cases."""
    have = {r["solver"] for r in recs if r.get("kind") == "run" and r.get("case") in cases}
    return [c for c in COMPETITORS if c in have]


def floor_err(e):
    return max(e, 1e-16)


def time_at(runs, target, key="error"):
    """(time, flag) at error `target` on the Pareto front; flag '' interpolated, '<=' upper
    bound (fastest run already better), None when not reached."""
    f = front([r for r in runs if r.get(key) is not None], key)
    if not f:
        return None, None
    if f[0][key] <= target:
        return f[0]["t_eval"], "<="
    for a, b in zip(f, f[1:]):
        if a[key] > target >= b[key]:
            la, lb = math.log(floor_err(a[key])), math.log(floor_err(b[key]))
            w = (math.log(target) - la) / (lb - la) if lb != la else 1.0
            return math.exp(math.log(a["t_eval"]) + w * (math.log(b["t_eval"]) -
                                                         math.log(a["t_eval"]))), ""
    return None, None


def direct_time(recs, case, n):
    """Time of the exact direct sum at N: measured; or, above the N where it runs on all atoms,
    the CPU time of the sampled reference's direct sum (all sources, the sampled targets)
    scaled by N / sampled (flag "s"); or extrapolated as N^2 from the largest measured N of
    the case (flag "~")."""
    runs = ok_runs(recs, case, n, "direct")
    if runs:
        return min(r["t_eval"] for r in runs), ""
    if is_periodic(recs, case):    # the exact Ewald sum was only run at small N
        return None, None
    ref = ref_of(recs, case, n)
    if ref and ref.get("c_direct_sum") and 0 < ref.get("sampled", 0) < ref["natoms"]:
        return ref["c_direct_sum"] * ref["natoms"] / ref["sampled"], "s"
    meas = [r for r in ok_runs(recs, case, None, "direct")]
    if not meas:
        return None, None
    r = max(meas, key=lambda r: r["natoms"])
    natoms = next((x["natoms"] for x in ok_runs(recs, case, n)), None)
    if natoms is None:
        return None, None
    return r["t_eval"] * (natoms / r["natoms"]) ** 2, "~"


def fmt_t(t, flag=""):
    if t is None:
        return "n/r"
    s = f"{t:.3g}" if t >= 1e-3 else f"{t:.2e}"
    return (flag or "") + s


def fmt_e(e):
    if e is None:
        return "-"
    return f"{e:.2e}"


def fmt_n(n):
    if n >= 1000 and n % 1000 == 0:
        k = n // 1000
        return f"{k // 1000}M" if k % 1000 == 0 else f"{k}k"
    return str(n)


def cases_of(recs, kind="run"):
    seen = []
    for r in recs:
        if r.get("kind") == kind and r["case"] not in seen:
            seen.append(r["case"])
    return seen


STATES = {"start": 0, "end": 1}


def nkey(n):
    """N of a series (int), or the state of a scene snapshot ("start", "end")."""
    return (0, n, "") if isinstance(n, int) else (1, STATES.get(n, 9), str(n))


def ns_of(recs, case):
    return sorted({r["n"] for r in recs if r.get("kind") == "run" and r["case"] == case},
                  key=nkey)


def nlabel(n, natoms):
    return str(natoms) if isinstance(n, int) else f"{natoms} ({n})"


def is_series(recs, case):
    ns = ns_of(recs, case)
    return len(ns) >= 2 and all(isinstance(n, int) for n in ns)


def ref_of(recs, case, n):
    for r in recs:
        if r.get("kind") == "reference" and r["case"] == case and r["n"] == n:
            return r
    return None


def ratio(a, b):
    if a is None or b is None or b <= 0:
        return None
    return a / b


def fmt_ratio(x, flag=""):
    if x is None:
        return "n/r"
    if flag == "s":
        return (f"{x:.3g}x" if x < 100 else f"{x:.0f}x") + " (s)"
    return f"{flag}{x:.3g}x" if x < 100 else f"{flag}{x:.0f}x"


# ----------------------------------------------------------------------------- plots

def make_plots(recs, outdir, cases, profile):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("report.py: matplotlib not available, no plots", file=sys.stderr)
        return {}
    files = {}
    for case in cases:
        ns = ns_of(recs, case)
        if not ns:
            continue
        ncol = min(len(ns), 4)
        fig, axes = plt.subplots(1, ncol, figsize=(4.2 * ncol, 4.0), squeeze=False)
        for ax, n in zip(axes[0], ns[-ncol:]):
            runs = ok_runs(recs, case, n)
            clumped = any(r.get("clump_error") is not None for r in runs)
            for solver in ("kifmm", "msm", "ewald", "pppm", "direct", "coulcut"):
                rs = [r for r in runs if r["solver"] == solver]
                if not rs:
                    continue
                c = COLORS[solver]
                lab = LABELS[solver] if n == ns[-ncol] else None
                if solver in EXACT:
                    # exact: a vertical line at its time (its error is round-off)
                    t = min(r["t_eval"] for r in rs)
                    ax.axvline(t, color=c, lw=1.0, ls="--", label=lab)
                    continue
                ax.scatter([r["t_eval"] for r in rs], [floor_err(r["error"]) for r in rs],
                           color=c, s=18, label=lab)
                if solver not in EXACT:
                    fr = front(rs)
                    ax.plot([r["t_eval"] for r in fr], [floor_err(r["error"]) for r in fr],
                            color=c, lw=1.2)
                if clumped and solver not in EXACT:
                    rc = [r for r in rs if r.get("clump_error") is not None]
                    ax.scatter([r["t_eval"] for r in rc], [floor_err(r["clump_error"]) for r in rc],
                               facecolors="none", edgecolors=c, s=22,
                               label=(f"{solver}: clump net-force error" if n == ns[-ncol]
                                      else None))
            if not any(r["solver"] == "direct" for r in runs):
                td, fd = direct_time(recs, case, n)
                if fd == "s":    # timed on the reference's sample, scaled by N / sample
                    ax.axvline(td, color=COLORS["direct"], lw=1.0, ls=":",
                               label="direct sum (timed on the sample, scaled)")
            for e in TARGETS:
                ax.axhline(e, color="0.8", lw=0.6, ls=":")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_ylim(3e-17, 0.3)
            natoms = runs[0]["natoms"] if runs else n
            ref = ref_of(recs, case, n)
            sampled = ref and ref.get("sampled", natoms) < natoms
            ax.set_title(f"{case}, N = {nlabel(n, natoms)}" +
                         (" (sampled ref.)" if sampled else ""), fontsize=9)
            ax.set_xlabel("CPU time per force evaluation [s]")
            ax.set_ylabel("relative force error")
            ax.grid(True, which="major", lw=0.3)
        for ax in axes[0]:
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=6, loc="best")
        fig.tight_layout()
        fn = os.path.join(outdir, f"pareto_{case}.png")
        fig.savefig(fn, dpi=110)
        plt.close(fig)
        files[f"pareto_{case}"] = fn

    # time versus N at matched error
    scal = [c for c in cases if is_series(recs, c)]
    if scal:
        ncol = min(len(scal), 3)
        nrow = (len(scal) + ncol - 1) // ncol
        fig, axes = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 4.0 * nrow), squeeze=False)
        for k, case in enumerate(scal):
            ax = axes[k // ncol][k % ncol]
            ns = ns_of(recs, case)
            natoms = {n: ok_runs(recs, case, n)[0]["natoms"] for n in ns if ok_runs(recs, case, n)}
            for solver, style in (("kifmm", "-"), ("msm", "--"), ("ewald", "--"),
                                  ("pppm", ":")):
                for e, mk in zip(TARGETS, ("o", "s", "^")):
                    xs, ys, bx, by = [], [], [], []
                    for n in ns:
                        t, flag = time_at(ok_runs(recs, case, n, solver), e)
                        if t is not None and n in natoms:
                            xs.append(natoms[n])
                            ys.append(t)
                            if flag == "<=":
                                bx.append(natoms[n])
                                by.append(t)
                    if xs and (solver == "kifmm" or e != TARGETS[-1] or len(xs) > 1):
                        ax.plot(xs, ys, style, marker=mk, color=COLORS[solver], ms=4,
                                label=f"{solver} @ {e:.0e}")
                        # upper bounds (the fastest run already more accurate): hollow
                        ax.scatter(bx, by, marker=mk, s=30, facecolors="white",
                                   edgecolors=COLORS[solver], zorder=3)
            xs, ys, xe, ye, xsm, ysm = [], [], [], [], [], []
            for n in ns:
                t, flag = direct_time(recs, case, n)
                if t is not None and n in natoms:
                    xl, yl = (xe, ye) if flag == "~" else ((xsm, ysm) if flag == "s" else (xs, ys))
                    xl.append(natoms[n])
                    yl.append(t)
            if xs:
                ax.plot(xs, ys, "-", marker="d", color=COLORS["direct"], ms=4, label="direct")
            if xsm:
                ax.plot(xs[-1:] + xsm, ys[-1:] + ysm, "--", marker="d", mfc="none",
                        color=COLORS["direct"], ms=5,
                        label="direct (sampled targets, scaled by N/sample)")
            if xe:
                ax.plot(xs[-1:] + xe, ys[-1:] + ye, ":", marker="d", mfc="none",
                        color=COLORS["direct"], ms=4, label="direct (N^2 extrapolated)")
            # O(N) guide through kifmm's first point at 1e-5 with N >= 5000 (below, kifmm's
            # octree has at most a level or two, mostly near field)
            t0 = [(natoms[n], time_at(ok_runs(recs, case, n, "kifmm"), 1e-5)[0]) for n in ns
                  if n in natoms and natoms[n] >= 5000]
            t0 = [p for p in t0 if p[1] is not None]
            if t0:
                x0, y0 = t0[0]
                xx = [x0, max(natoms.values())]
                ax.plot(xx, [y0 * x / x0 for x in xx], color="0.5", lw=0.8, ls="-.",
                        label="O(N) guide")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(case + " (hollow: upper bound)", fontsize=9)
            ax.set_xlabel("N (atoms)")
            ax.set_ylabel("CPU time per force evaluation [s]")
            ax.grid(True, lw=0.3)
            ax.legend(fontsize=6)
        for k in range(len(scal), nrow * ncol):
            axes[k // ncol][k % ncol].axis("off")
        fig.tight_layout()
        fn = os.path.join(outdir, "time_vs_n.png")
        fig.savefig(fn, dpi=110)
        plt.close(fig)
        files["time_vs_n"] = fn

    # error versus order (kifmm, explicit and calibrated orders) at each case's largest N
    fig, ax = plt.subplots(figsize=(5.5, 4.0))
    any_line = False
    for case in cases:
        ns = ns_of(recs, case)
        for n in [order_n(recs, case)] if ns else []:
            rs = [r for r in ok_runs(recs, case, n, "kifmm") if r.get("order")]
            byo = {}
            for r in rs:
                byo.setdefault(r["order"], []).append(r["error"])
            if len(byo) >= 2:
                os_ = sorted(byo)
                ax.plot(os_, [floor_err(min(byo[o])) for o in os_], marker="o", ms=4,
                        label=f"{case} N={rs[0]['natoms']}")
                any_line = True
    if any_line:
        ax.set_yscale("log")
        ax.set_xlabel("kifmm order P (points per surface edge)")
        ax.set_ylabel("relative force error")
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fn = os.path.join(outdir, "error_vs_order.png")
        fig.savefig(fn, dpi=110)
        files["error_vs_order"] = fn
    plt.close(fig)
    # Pareto plots of cases without results here (an older campaign's) would be stale
    for fn in os.listdir(outdir):
        if re.fullmatch(r"pareto_.*\.png", fn) and fn[:-4] not in files:
            os.remove(os.path.join(outdir, fn))
    return files


# ----------------------------------------------------------------------------- tables

def ref_history_note(recs, results_path):
    """Whether the current references (remade in a fresh work directory) are the same atoms
    as the earlier references of the same case and N in the results file (same atom count,
    sample and RMS force), and whether the re-measured stored runs gave the same errors."""
    if not results_path or not os.path.exists(results_path):
        return ""
    hist = {}
    with open(results_path) as f:
        for line in f:
            try:
                r = json.loads(line)
            except json.JSONDecodeError:
                continue
            if r.get("kind") == "reference":
                hist.setdefault((r["case"], r["n"]), []).append(r)
    same, diff, earlier = 0, [], set()
    for key, v in hist.items():
        cur = v[-1]
        prev = [r for r in v[:-1] if r.get("commit") != cur.get("commit")]
        if not prev:
            continue
        earlier.add(str(prev[-1].get("commit")))
        ok = (prev[-1].get("sampled") == cur.get("sampled") and same_atoms(prev[-1], cur))
        if ok:
            same += 1
        else:
            diff.append(f"{key[0]} {key[1]}")
    txt = ""
    if same or diff:
        txt = (f"Remade in a fresh work directory for the kifmm runs: {same} of {same + len(diff)}"
               f" references are the same atoms as the earlier references of the same case and "
               f"N (of {', '.join(sorted(earlier))}; same atom count, sample and RMS force)" +
               (f", the others ({', '.join(diff)}) are remade scene snapshots, see [Hard "
                "cases](#hard-cases)" if diff else "") + ".")
    kc = kifmm_commit(recs)
    stored = {(r["case"], r["n"], r["spec"]): r for r in ok_runs(recs)}
    n_same, n_all, dev = 0, 0, []
    for r in side_records(results_path, r"recheck-.*\.jsonl"):
        old = stored.get((r.get("case"), r.get("n"), r.get("spec")))
        if r.get("commit") != kc or r.get("status") != "ok" or old is None:
            continue
        if r.get("solver") == "kifmm":
            continue
        n_all += 1
        exact = (r.get("solver") in EXACT and
                 max(r.get("error") or 0, old.get("error") or 0) < 1e-12)
        if r.get("error") == old.get("error") or exact:
            n_same += 1
        else:
            dev.append(f"{r['case']} {r['n']} {r['spec']}: {fmt_e(r.get('error'))} "
                       f"(stored {fmt_e(old.get('error'))})")
    if n_all:
        txt += (f" Of the {n_all} stored competitor settings re-measured on these references "
                f"at the time of the kifmm runs, {n_same} gave the stored error to all digits (the "
                f"exact sums: to round-off, below 1e-12)" +
                (": " + "; ".join(dev) if dev else "") + ".")
    return txt


def settings_table(recs, results_path=None):
    runs = [r for r in recs if r.get("kind") == "run" and r.get("status") != "skipped"]
    if not runs:
        return "(no results)\n"
    loads = [x for r in runs for x in r.get("load", []) if x >= 0]
    threads = sorted({str(r.get("omp_threads", r.get("omp_threads_env"))) for r in runs})
    cpus = sorted({str(r.get("host_cpus")) for r in runs})

    def commits(rs):
        return ", ".join(sorted({str(r.get("commit") or "?") for r in rs})) or "-"

    def dates(rs):
        d = sorted(r["date"] for r in rs if r.get("date"))
        return f"{d[0]} to {d[-1]}" if d else "-"

    kif = [r for r in runs if r.get("solver") == "kifmm"]
    comp = [r for r in runs if r.get("solver") != "kifmm"]
    setup = [r for r in recs if r.get("kind") == "setup"]
    refs = [r for r in recs if r.get("kind") == "reference"]
    nok = sum(1 for r in runs if r.get("kind") == "run" and r.get("status") == "ok")
    nfail = sum(1 for r in runs if r.get("kind") == "run" and r.get("status") != "ok")
    lines = ["| setting | value |", "|---|---|",
             f"| kifmm runs: source commit, measured | {commits(kif)} (engine and styles of "
             f"that commit, built from a clean checkout of it), {dates(kif)} |",
             f"| kifmm operator setup table: source commit | {commits(setup)} |",
             f"| competitor runs (msm, ewald, pppm, direct, coulcut): source commit, measured | "
             f"{commits(comp)}, {dates(comp)}. Their code (LAMMPS's styles, kifmm::direct_sum, "
             "kifmm::periodic_direct_sum) and the `run` command of bench_solvers are the same "
             "at these commits; `+dirty`: the checkout had an uncommitted timer in the "
             "engine's fmm_core.h, which only kifmm runs use |",
             f"| source commit of the references (same data files and reference forces for "
             f"every solver) | {commits(refs)}. " + ref_history_note(recs, results_path) +
             " |",
             "| earlier kifmm runs | " + ", ".join(
                 f"bench/solvers/results/{fn} (engine at {fn[len('kifmm-'):-len('.jsonl')]})"
                 for fn in (archives(results_path) if results_path else [])) +
             ": **not used in this report** except in the tables [kifmm runs of earlier "
             "engine commits](#kifmm-runs-of-earlier-engine-commits) |",
             f"| OMP_NUM_THREADS (kifmm engine, direct sum) | {', '.join(threads)} |",
             "| MPI ranks | 1 (LAMMPS styles msm, coul/msm, coul/cut are serial) |",
             f"| host CPUs (shared with other work) | {', '.join(cpus)} |",
             (f"| 1-min load average during the runs | {min(loads):.1f} to {max(loads):.1f} |"
              if loads else "| load average | - |"),
             f"| solver runs | {nok} ok, {nfail} failed or stopped (listed in the tables) |"]
    return "\n".join(lines) + "\n"


def limit_runs(recs):
    """The runs made with a per-run CPU limit other than the profile's (cpu_limit_s)."""
    std = {600, 300}
    by = {}
    for r in recs:
        c = r.get("cpu_limit_s")
        if r.get("kind") == "run" and c is not None and c not in std:
            by.setdefault(c, []).append(f"{r['case']} N = {r['n']} {r['spec']} ({r['status']})")
    return "; ".join(f"{c:g} s CPU: " + ", ".join(v) for c, v in sorted(by.items()))


def side_records(results_path, pattern):
    """Records of the JSON-lines files next to the results file whose names match pattern
    (archived or re-measured runs that the report shows apart)."""
    d = os.path.dirname(os.path.abspath(results_path))
    try:
        files = sorted(f for f in os.listdir(d) if re.fullmatch(pattern, f))
    except OSError:
        files = []
    out = []
    for fn in files:
        with open(os.path.join(d, fn)) as f:
            for line in f:
                try:
                    out.append(json.loads(line))
                except json.JSONDecodeError:
                    continue
                all_atom_error(out[-1])
    return out


def recheck_table(recs, results_path):
    """Settings measured again later with the same command, data and reference
    (results/recheck-*.jsonl next to the results file): stored and new CPU time."""
    stored = {(r["case"], r["n"], r["spec"]): r for r in ok_runs(recs)}
    lines = []
    for r in side_records(results_path, r"recheck-.*\.jsonl"):
        old = stored.get((r.get("case"), r.get("n"), r.get("spec")))
        if r.get("status") != "ok" or "c_eval" not in r or old is None:
            continue
        if r.get("solver") == "kifmm" and r.get("commit") != old.get("commit"):
            continue    # a re-measured kifmm run of another engine than the stored one
        same = r.get("error") == old.get("error")
        lines.append(f"| {r['case']} | {r['n']} | {r['spec']} | {fmt_t(old['t_eval'])} "
                     f"({old.get('commit')}, {old.get('date', '?')[5:16]}) | "
                     f"{fmt_t(r['c_eval'])} ({r.get('date', '?')[5:16]}) | "
                     f"{r['c_eval'] / old['t_eval']:.2f} | "
                     f"{'same' if same else fmt_e(r.get('error'))} |")
    if not lines:
        return ""
    return "\n".join(["| case | N | setting | stored CPU eval [s] | re-measured [s] | ratio | "
                      "error |", "|---|---|---|---|---|---|---|"] + lines) + "\n"


def median(v):
    """Median of a sorted, non-empty list."""
    return v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])


def recheck_groups(recs, results_path):
    """(day, commit) -> {"competitors": [...], "kifmm": [...]}: re-measured / stored CPU time
    per evaluation of the recheck records (kifmm: only those of the stored kifmm runs' engine)."""
    stored = {(r["case"], r["n"], r["spec"]): r for r in ok_runs(recs)}
    by = {}
    for r in side_records(results_path, r"recheck-.*\.jsonl"):
        old = stored.get((r.get("case"), r.get("n"), r.get("spec")))
        if r.get("status") != "ok" or "c_eval" not in r or old is None or not old["t_eval"]:
            continue
        kif = r.get("solver") == "kifmm"
        if kif and r.get("commit") != old.get("commit"):
            continue
        by.setdefault((r.get("date", "?")[:10], r.get("commit")), {}).setdefault(
            "kifmm" if kif else "competitors", []).append(r["c_eval"] / old["t_eval"])
    return by


def recheck_summary(recs, results_path):
    """One sentence per date and binary of re-measurements: median and range of re-measured / stored
    CPU time of the competitors' settings and of kifmm's."""
    out = []
    for (day, commit), groups in sorted(recheck_groups(recs, results_path).items(),
                                        key=lambda x: str(x[0])):
        parts = []
        for g in ("competitors", "kifmm"):
            v = sorted(groups.get(g, []))
            if v:
                med = median(v)
                parts.append(f"{g} ({len(v)} settings) {med:.2f} ({v[0]:.2f} - {v[-1]:.2f})")
        out.append(f"Re-measured with the binary of {commit} ({day}), new / stored CPU time per "
                   "evaluation, median (min - max): " + ", ".join(parts) + ".")
    return " ".join(out)


def retime_factor(recs, results_path, commit, group="competitors"):
    """(median, min, max, count) of re-measured / stored CPU time of the recheck records made
    with the binary of `commit` (at the time of that commit's kifmm runs), or None."""
    v = sorted(x for (_, c), g in recheck_groups(recs, results_path).items() if c == commit
               for x in g.get(group, []))
    return (median(v), v[0], v[-1], len(v)) if v else None


def kifmm_commit(recs):
    """The source commit of most of the ok kifmm runs (the engine of this report)."""
    count = {}
    for r in ok_runs(recs, solver="kifmm"):
        count[r.get("commit")] = count.get(r.get("commit"), 0) + 1
    return max(count, key=count.get) if count else None


def archive_timing_note(recs, results_path, archive):
    """How CPU times at the time of the archived runs compare with those at the time of this
    report's kifmm runs: the stored competitor settings re-measured at each (recheck-COMMIT.jsonl)."""
    commit = archive[len("kifmm-"):-len(".jsonl")]
    fa = retime_factor(recs, results_path, commit)
    fn = retime_factor(recs, results_path, kifmm_commit(recs))
    if not fa or not fn:
        return ""
    return (f" Stored competitor settings re-measured after the archived runs "
            f"(results/recheck-{commit}.jsonl) took a median {fa[0]:.2f}x their stored CPU "
            f"time ({fa[3]} settings), after this report's kifmm runs "
            f"{fn[0]:.2f}x ({fn[3]} settings): the same work took about {fn[0] / fa[0]:.2f}x "
            "as much CPU time at the time of this report's runs, so a ratio new / old near that value "
            "means an unchanged speed of the engine.")


def ratio_table(recs, cases):
    comps = competitors(recs, cases) + ["direct"]
    hdr = "| case | N |"
    sep = "|---|---|"
    for e in TARGETS:
        hdr += f" kifmm @ {e:.0e} [s] |" + "".join(f" {c} / kifmm |" for c in comps)
        sep += "---|" * (1 + len(comps))
    lines = [hdr, sep]
    for case in cases:
        for n in ns_of(recs, case):
            runs = ok_runs(recs, case, n)
            if not runs:
                continue
            row = f"| {case} | {nlabel(n, runs[0]['natoms'])} |"
            for e in TARGETS:
                tk, fk = time_at(ok_runs(recs, case, n, "kifmm"), e)
                row += f" {fmt_t(tk, fk)} |"
                for c in comps:
                    if c == "direct":
                        tc, fc = direct_time(recs, case, n)
                    else:
                        tc, fc = time_at(ok_runs(recs, case, n, c), e)
                    tried = [r for r in recs if r.get("kind") == "run" and r["case"] == case
                             and r["n"] == n and r.get("solver") == c]
                    if not tried:
                        row += " - |"
                        continue
                    if not any(r["status"] == "ok" for r in tried):
                        row += " failed |"
                        continue
                    # a ratio with a bound or an extrapolated time is marked approximate; a
                    # direct-sum time scaled from the sampled reference is marked s
                    flag = "~" if (fc in ("<=", "~") or fk == "<=") else (
                        "s" if fc == "s" else "")
                    row += f" {fmt_ratio(ratio(tc, tk), flag) if tc else 'n/r'} |"
            lines.append(row)
    return "\n".join(lines) + "\n"


def runs_table(recs, case):
    ns = ns_of(recs, case)
    clumped = any(r.get("clump_error") is not None for r in ok_runs(recs, case))
    hdr = "| solver | N | error |" + (" clump net-force error |" if clumped else "") + \
        " eval, CPU [s] | pair / kspace, CPU [s] | setup, CPU [s] | memory [MB] | runs | status |"
    sep = "|---|---|---|" + ("---|" if clumped else "") + "---|---|---|---|---|---|"
    lines = [hdr, sep]
    for n in ns:
        rs = [r for r in recs if r.get("kind") == "run" and r["case"] == case and r["n"] == n]
        order = {"kifmm": 0, "msm": 1, "ewald": 2, "pppm": 3, "direct": 4, "coulcut": 5}
        rs.sort(key=lambda r: (order.get(r["solver"], 9), r.get("order") or 0, r["spec"]))
        for r in rs:
            spec = r["spec"]
            if r["solver"] == "kifmm" and r.get("order"):
                spec += f" (P={r['order']})"
            if r["status"] != "ok":
                lines.append(f"| {spec} | {r.get('natoms', n)} | - |" + (" - |" if clumped else "")
                             + f" - | - | - | - | - | {r['status']}: {r['message']} |")
                continue
            ce = fmt_e(r.get("clump_error")) if clumped else None
            pk = (f"{r['t_pair']:.3g} / {r['t_kspace']:.3g}" if r["solver"] not in ("direct",)
                  else "-")
            lines.append(f"| {spec} | {nlabel(n, r['natoms'])} | {fmt_e(r['error'])} |" +
                         (f" {ce} |" if clumped else "") +
                         f" {fmt_t(r['t_eval'])} | {pk} | {r['t_setup']:.3g} | {r['mem_mb']:.0f} |"
                         f" {r['repeats']} | ok |")
    return "\n".join(lines) + "\n"


def summary(recs, cases, rechecks=None):
    """One line per case at its largest N: kifmm's speed ratios at matched error (and, where
    every run of a competitor there was re-measured at the time of the kifmm runs, that ratio)."""
    rechecks = rechecks or {}
    lines = []
    for case in cases:
        ns = [n for n in ns_of(recs, case) if ok_runs(recs, case, n, "kifmm")]
        if not ns:
            continue
        n = ns[-1]
        natoms = ok_runs(recs, case, n)[0]["natoms"]
        td, fd = direct_time(recs, case, n)
        comps = [c for c in COMPETITORS if any(r.get("kind") == "run" and r["case"] == case
                                               and r.get("solver") == c for r in recs)]
        failed = {}
        for c in comps:
            rs = [r for r in recs if r.get("kind") == "run" and r["case"] == case and
                  r["n"] == n and r.get("solver") == c]
            if rs and not any(r["status"] == "ok" for r in rs):
                why = set()
                for r in rs:
                    m = re.search(r"ERROR(?: on proc \d+)?: ([^,(]*)", r.get("message", ""))
                    why.add(m.group(1).strip() if m else (
                        f"skipped: {r.get('message', '')}" if r["status"] == "skipped"
                        else r["status"]))
                failed[c] = f"{c}: all {len(rs)} settings failed ({'; '.join(sorted(why))})"
        parts = []
        for e in TARGETS:
            tk, fk = time_at(ok_runs(recs, case, n, "kifmm"), e)
            if tk is None:
                parts.append(f"{e:.0e}: kifmm n/r")
                continue
            items = []
            for c in comps:
                if c in failed:
                    continue
                if not any(r.get("kind") == "run" and r["case"] == case and r["n"] == n
                           and r.get("solver") == c for r in recs):
                    items.append(f"{c} not run at this N yet")
                    continue
                tc, fc = time_at(ok_runs(recs, case, n, c), e)
                same = retimed_runs(recs, rechecks, case, n, c)
                ts, fs = time_at(same, e) if same else (None, None)
                items.append(fmt_ratio(ratio(tc, tk), "~" if "<=" in (fk, fc) else "") +
                             f" vs {c}" + (f" (re-measured with the kifmm runs: " +
                                           fmt_ratio(ratio(ts, tk), "~" if "<=" in (fk, fs)
                                                     else "") + ")" if ts else "")
                             if tc is not None else f"{c} n/r")
            if td is not None:
                items.append(fmt_ratio(ratio(td, tk), "~" if (fd == "~" or fk == "<=") else
                                       ("s" if fd == "s" else "")) + " vs direct")
            parts.append(f"{e:.0e}: " + ", ".join(items))
        ref = ref_of(recs, case, n)
        samp = " (sampled reference)" if ref and ref["sampled"] < ref["natoms"] else ""
        per = " periodic" if is_periodic(recs, case) else ""
        tail = "".join(f" {failed[c]}." for c in comps if c in failed)
        # a competitor without results at this N: its ratios at the largest N where it ran
        for c in comps:
            if ok_runs(recs, case, n, c):
                continue
            n2 = [m for m in ns if ok_runs(recs, case, m, c) and ok_runs(recs, case, m, "kifmm")]
            if not n2:
                continue
            m = n2[-1]
            rs = []
            for e in TARGETS:
                mt = matched(recs, case, m, c, e)
                rs.append(f"{e:.0e}: " + (fmt_ratio(mt[1] / mt[0], "~" if mt[2] else "")
                                          if mt else "n/r"))
            tail += (f" At N = {nlabel(m, ok_runs(recs, case, m)[0]['natoms'])}, the largest "
                     f"where {c} ran: " + ", ".join(rs) + f" vs {c}.")
        lines.append(f"* **{case}**{per}, N = {nlabel(n, natoms)}{samp}: " + "; ".join(parts)
                     + "." + tail)
    return "\n".join(lines) + "\n"


def reference_table(recs, cases):
    lines = ["| case | N | reference atoms | RMS force | time [s] | clump scale |",
             "|---|---|---|---|---|---|"]
    for case in cases:
        for n in ns_of(recs, case):
            r = ref_of(recs, case, n)
            if not r:
                continue
            lines.append(f"| {case} | {nlabel(n, r['natoms'])} | "
                         f"{'all' if r['sampled'] >= r['natoms'] else str(r['sampled']) + ' sampled'}"
                         f" | {r['f_rms']:.4g} | {r['time']:.3g} | {r.get('clump_scale', 1):.3g} |")
    return "\n".join(lines) + "\n"


def scaling_table(recs, cases):
    lines = ["| case | error | N range | kifmm times [s] | fitted exponent (time ~ N^k) |",
             "|---|---|---|---|---|"]
    for case in cases:
        ns = ns_of(recs, case)
        if not is_series(recs, case):
            continue
        for e in TARGETS:
            pts = []
            for n in ns:
                t, flag = time_at(ok_runs(recs, case, n, "kifmm"), e)
                runs = ok_runs(recs, case, n)
                if t is not None and runs:
                    pts.append((runs[0]["natoms"], t))
            # at N ~ 1e3 kifmm's tree is one or two levels, mostly near field: fit from
            # N >= 5000
            pts = [p for p in pts if p[0] >= 5000]
            if len(pts) < 2:
                continue
            xs = [math.log(p[0]) for p in pts]
            ys = [math.log(p[1]) for p in pts]
            mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
            den = sum((x - mx) ** 2 for x in xs)
            k = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / den if den else float("nan")
            lines.append(f"| {case} | {e:.0e} | {pts[0][0]} - {pts[-1][0]} | "
                         f"{', '.join(fmt_t(p[1]) for p in pts)} | {k:.2f} |")
    return "\n".join(lines) + "\n"


def archived_runs(results_path, archive):
    """(case, n, spec) -> ok kifmm run with a CPU time in the archive file `archive` (a
    results/kifmm-COMMIT.jsonl next to the results file)."""
    return {(r["case"], r["n"], r["spec"]): r
            for r in side_records(results_path, re.escape(archive))
            if r.get("kind") == "run" and r.get("status") == "ok" and "c_eval" in r}


def engine_change_table(recs, results_path, archive):
    """kifmm runs of this report against the archived kifmm runs of an earlier engine
    (results/kifmm-COMMIT.jsonl next to the results file, the file name `archive`): same case,
    N and spec, same data and reference files; the ratio of CPU times per evaluation and of
    the errors."""
    old = archived_runs(results_path, archive)
    if not old:
        return ""
    lines = ["| case | N | settings | CPU eval new / old: median (min - max) | "
             "error new / old (min - max) | old commit |", "|---|---|---|---|---|---|"]
    for case in cases_of(recs):
        for n in ns_of(recs, case):
            pairs = [(r, old[(case, n, r["spec"])]) for r in ok_runs(recs, case, n, "kifmm")
                     if (case, n, r["spec"]) in old
                     and same_atoms(r, old[(case, n, r["spec"])])]
            if not pairs:
                continue
            tr = sorted(a["t_eval"] / b["c_eval"] for a, b in pairs if b["c_eval"] > 0)
            er = sorted(a["error"] / b["error"] for a, b in pairs if b.get("error"))
            med = median(tr)
            ecol = f"{er[0]:.3g} - {er[-1]:.3g}" if er else "-"
            oc = ", ".join(sorted({str(b.get("commit")) for _, b in pairs}))
            lines.append(f"| {case} | {nlabel(n, pairs[0][0]['natoms'])} | {len(pairs)} | "
                         f"{med:.2f} ({tr[0]:.2f} - {tr[-1]:.2f}) | {ecol} | {oc} |")
    return "\n".join(lines) + "\n"


def same_atoms(a, b):
    """Two runs on the same atoms and reference (a scene snapshot made again from a changed
    example is not): same atom count and RMS reference force."""
    fa, fb = a.get("f_rms"), b.get("f_rms")
    return (a.get("natoms") == b.get("natoms") and fa is not None and fb is not None
            and abs(fa - fb) <= 1e-6 * abs(fb))


def depth_change_summary(recs, results_path, archive):
    """One paragraph: the CPU time ratios new / archived grouped by how the tree depth changed
    (a single leaf now or before; else same, deeper or shallower tree, at N >= 5e4 and below)."""
    old = archived_runs(results_path, archive)
    groups = {}
    for r in ok_runs(recs, solver="kifmm"):
        o = old.get((r["case"], r["n"], r["spec"]))
        if o is None or not same_atoms(r, o) or o.get("depth") is None or r.get("depth") is None:
            continue
        q = r["t_eval"] / o["c_eval"]
        big = "big" if r["natoms"] >= 50000 else "small"
        if r["depth"] == 0 and o["depth"] > 0:
            g = "zero"
        elif o["depth"] == 0 and r["depth"] > 0:
            g = "from_zero"
        elif r["depth"] == o["depth"]:
            g = "same_" + big
        else:
            g = ("deeper_" if r["depth"] > o["depth"] else "shallower_") + big
        groups.setdefault(g, []).append(q)

    def st(v):
        v = sorted(v)
        med = median(v)
        return f"{len(v)} settings, median {med:.2f} ({v[0]:.2f} - {v[-1]:.2f})"
    words = {"same_big": "N >= 5e4 with the same tree depth as before",
             "deeper_big": "N >= 5e4 with a deeper tree",
             "shallower_big": "N >= 5e4 with a shallower tree",
             "same_small": "N < 5e4 with the same tree depth",
             "deeper_small": "N < 5e4 with a deeper tree (not a single leaf before)",
             "shallower_small": "N < 5e4 with a shallower tree (not a single leaf now)",
             "zero": "a single leaf (depth 0) where the tree had depth >= 1",
             "from_zero": "a tree of depth >= 1 where it was a single leaf (depth 0)"}
    parts = [f"{words[g]}: {st(groups[g])}" for g in words if g in groups]
    return ("CPU eval new / old by tree depth (`depth` in the records): " + "; ".join(parts) +
            ".") if parts else ""


def archives(results_path):
    """File names of the archived kifmm runs next to the results file: those of ARCHIVES
    (newest first), then any other kifmm-*.jsonl."""
    d = os.path.dirname(os.path.abspath(results_path))
    try:
        files = sorted(f for f in os.listdir(d) if re.fullmatch(r"kifmm-.*\.jsonl", f))
    except OSError:
        files = []
    return [f for f in ARCHIVES if f in files] + [f for f in files if f not in ARCHIVES]


def order_n(recs, case):
    """The largest N of a case with kifmm runs at explicit orders (the 1e6 runs have
    calibrated accuracies only), else its largest N."""
    ns = ns_of(recs, case)
    exp = [n for n in ns if any("order=" in r["spec"] for r in ok_runs(recs, case, n, "kifmm"))]
    return (exp or ns or [None])[-1]


def order_table(recs, cases):
    rows = []
    for case in cases:
        n = order_n(recs, case)
        if n is None:
            continue
        rs = [r for r in ok_runs(recs, case, n, "kifmm") if r.get("order")]
        byo = {}
        for r in rs:
            if r["order"] not in byo or r["error"] < byo[r["order"]]["error"]:
                byo[r["order"]] = r
        if byo:
            rows.append((case, rs[0]["natoms"], byo))
    orders = sorted({o for _, _, b in rows for o in b})
    if not orders:
        return "(no kifmm runs)\n"
    lines = ["| case | N | " + " | ".join(f"P={o}" for o in orders) + " | falls monotonically |",
             "|---|---|" + "---|" * len(orders) + "---|"]
    for case, natoms, b in rows:
        errs = [b[o]["error"] for o in orders if o in b]
        mono = all(y <= x * 1.5 for x, y in zip(errs, errs[1:]))
        lines.append(f"| {case} | {natoms} | " +
                     " | ".join(fmt_e(b[o]["error"]) if o in b else "-" for o in orders) +
                     f" | {'yes' if mono else 'NO'} |")
    return "\n".join(lines) + "\n"


def accuracy_table(recs, cases):
    """kifmm runs at a requested accuracy (spec acc=A): per case, the runs, the largest and
    smallest measured error / A, and the runs whose error exceeds A."""
    lines = ["| case | runs | error / request: max (run) | min (run) | above the request | "
             "below 1/5 of the request, the order below met it on the same tree |",
             "|---|---|---|---|---|---|"]
    over_all = low_all = unchecked_all = 0
    for case in cases:
        rs, kifmm = [], ok_runs(recs, case, solver="kifmm")
        for r in kifmm:
            m = re.search(r"acc=([0-9.eE+-]+)", r["spec"])
            if m and r.get("error") is not None:
                rs.append((r["error"] / float(m.group(1)), r))
        if not rs:
            continue
        rs.sort(key=lambda x: x[0])
        over = [f"{nlabel(r['n'], r['natoms'])} {r['spec'][len('kifmm:'):]}: {q:.2f}"
                for q, r in rs if q > 1.0]
        over_all += len(over)
        low = [f"{nlabel(r['n'], r['natoms'])} {r['spec'][len('kifmm:'):]}: {q:.2g} (order {r['order_used']}; "
               f"{r['order_used'] - 1}: {below:.2f})" for q, r, below in order_below_met(rs, kifmm) if q < 0.2]
        low_all += len(low)
        unchecked_all += sum(1 for q, r in rs if q < 0.2 and "order_used" not in r)

        def at(x):
            return f"{x[0]:.3g} ({nlabel(x[1]['n'], x[1]['natoms'])}, {x[1]['spec'][len('kifmm:'):]})"
        lines.append(f"| {case} | {len(rs)} | {at(rs[-1])} | {at(rs[0])} | "
                     f"{'; '.join(over) if over else 'none'} | {'; '.join(low) if low else 'none'} |")
    if len(lines) == 2:
        return ""
    return ("\n".join(lines) + "\n\n" + (f"{over_all} run(s) above the request" if over_all
                                         else "Every run met its request") +
            f"; {low_all} run(s) more than 5x below it where the order below met it on the same tree" +
            (f" ({unchecked_all} run(s) more than 5x below it recorded without the order used, not checked)"
             if unchecked_all else "") + ".\n")


def order_below_met(rs, kifmm):
    """(error / A, run, error of the order below / A) for the runs at acc=A where a run of the
    same case and N at the order below, on the same tree (leaf size and grid), measured an error
    <= A, and that tree has a far field (an error above 1e-12: else every order is the direct sum).
    The order of a run is the one it used (order_used); runs recorded without it are skipped."""
    out = []
    for q, r in rs:
        if "order_used" not in r:
            continue
        a = r["error"] / q if q > 0 else 0.0
        for o in kifmm:
            if (o["n"] == r["n"] and o.get("order_used", o.get("order") if "order=" in o["spec"] else None)
                    == r["order_used"] - 1 and o.get("leaf") == r.get("leaf")
                    and o.get("grid") == r.get("grid") and 1e-12 < o["error"] <= a):
                out.append((q, r, o["error"] / a))
                break
    return out


def setup_table(recs):
    rs = [r for r in recs if r.get("kind") == "setup" and r.get("status") == "ok"]
    if not rs:
        return "(not measured in this profile)\n"
    by = {}
    for r in rs:
        cold = "cache=none" in r["spec"]
        by.setdefault(r["order"], {})["cold" if cold else "warm"] = r
    cpu = all("c_setup" in r and "c_eval" in r for r in rs)
    lines = [f"Uniform cube of {rs[0]['natoms']} atoms; setup = first `run 0` (includes one "
             "evaluation with energy); overhead = setup - eval. " +
             ("CPU times." if cpu else "**Wall times** (these setup records have no CPU times; "
              "the table is not used in any ratio).") + "\n",
             "| order P | eval [s] | setup, no cache [s] | overhead, no cache [s] | "
             "setup, operators from the disk cache [s] | overhead, cached [s] | operators [MB] |",
             "|---|---|---|---|---|---|---|"]

    def st(r):
        return r.get("c_setup", r["t_setup"])

    for o in sorted(by):
        c, w = by[o].get("cold"), by[o].get("warm")
        if not c:
            continue
        lines.append(f"| {o} | {fmt_t(c['t_eval'])} | {st(c):.3g} | "
                     f"{max(0.0, st(c) - c['t_eval']):.3g} | " +
                     (f"{st(w):.3g} | {max(0.0, st(w) - w['t_eval']):.3g}"
                      if w else "- | -") + f" | {c.get('operator_mb', 0):.1f} |")
    return "\n".join(lines) + "\n"


def hard_table(recs, cases):
    lines = ["| case | N | solver | error (atoms) | clump net-force error | "
             "RMS clump net force / RMS atom force | eval [s] |", "|---|---|---|---|---|---|---|"]
    any_row = False
    for case in cases:
        for n in ns_of(recs, case):
            rs = [r for r in ok_runs(recs, case, n) if r.get("clump_error") is not None
                  and r["solver"] not in EXACT]
            for solver in ("kifmm",) + COMPETITORS:
                for r in front([x for x in rs if x["solver"] == solver]):
                    any_row = True
                    lines.append(f"| {case} | {nlabel(n, r['natoms'])} | {r['spec']} | "
                                 f"{fmt_e(r['error'])} | {fmt_e(r['clump_error'])} | "
                                 f"{r['clump_f_rms'] / r['f_rms']:.3g} | {fmt_t(r['t_eval'])} |")
    return ("\n".join(lines) + "\n") if any_row else "(no clump cases in these results)\n"


def clump_ratio_table(recs, cases):
    """Matched error on the clump net forces (what moves a rigid clump)."""
    cases = [c for c in cases if any(r.get("clump_error") is not None
                                     for r in ok_runs(recs, c))]
    if not cases:
        return ""
    comps = competitors(recs, cases)
    hdr = "| case | N |" + "".join(f" kifmm @ {e:.0e} [s] |" + "".join(
        f" {c} / kifmm |" for c in comps) for e in TARGETS)
    lines = [hdr, "|---|---|" + ("---|" * (1 + len(comps))) * len(TARGETS)]
    for case in cases:
        for n in ns_of(recs, case):
            runs = [r for r in ok_runs(recs, case, n) if r.get("clump_error") is not None]
            if not runs:
                continue
            row = f"| {case} | {nlabel(n, runs[0]['natoms'])} |"
            for e in TARGETS:
                tk, fk = time_at([r for r in runs if r["solver"] == "kifmm"], e, "clump_error")
                row += f" {fmt_t(tk, fk)} |"
                for c in comps:
                    cr = [r for r in runs if r["solver"] == c]
                    if not cr:
                        row += " - |"
                        continue
                    tc, fc = time_at(cr, e, "clump_error")
                    flag = "~" if "<=" in (fk, fc) else ""
                    row += f" {fmt_ratio(ratio(tc, tk), flag) if tc else 'n/r'} |"
            lines.append(row)
    return "\n".join(lines) + "\n"


def matched(recs, case, n, comp, e):
    """(kifmm time, competitor time, approximate flag) at error e, or None."""
    tk, fk = time_at(ok_runs(recs, case, n, "kifmm"), e)
    if comp == "direct":
        tc, fc = direct_time(recs, case, n)
    else:
        tc, fc = time_at(ok_runs(recs, case, n, comp), e)
    if tk is None or tc is None:
        return None
    return tk, tc, (fk == "<=" or fc in ("<=", "~"))


def retimed_runs(recs, rechecks, case, n, solver):
    """The ok runs of a solver at (case, N) with the CPU times re-measured at the time of
    the kifmm runs there (recheck records of the kifmm runs' commit, same error), or None if
    not every run of that solver was re-measured."""
    kc = {r.get("commit") for r in ok_runs(recs, case, n, "kifmm")}
    runs = ok_runs(recs, case, n, solver)
    out = []
    for r in runs:
        x = rechecks.get((case, n, r["spec"]))
        if x is None or x.get("commit") not in kc:
            return None
        exact_both = solver in EXACT and max(x.get("error") or 0, r.get("error") or 0) < 1e-12
        if x.get("error") != r.get("error") and not exact_both:
            return None    # (exact sums: references remade to round-off, see the text)
        y = dict(r)
        y["t_eval"] = x["c_eval"]
        out.append(y)
    return out or None


def losses(recs, cases, rechecks=None):
    """Where kifmm is slower than another solver at matched error (ratio < 1). rechecks:
    (case, n, spec) -> a recheck record; where every run of the competitor at that case and N
    was re-measured at the time of the kifmm runs, the ratio at that time is shown too."""
    rechecks = rechecks or {}
    lines = []
    for case in cases:
        comps = [c for c in COMPETITORS if any(r.get("kind") == "run" and r["case"] == case
                                               and r.get("solver") == c for r in recs)]
        comps.append("direct")
        for n in ns_of(recs, case):
            runs = ok_runs(recs, case, n)
            if not runs:
                continue
            items = []
            for c in comps:
                es = []
                same = retimed_runs(recs, rechecks, case, n, c)
                for e in TARGETS:
                    m = matched(recs, case, n, c, e)
                    if m and m[1] < m[0]:
                        txt = (f"{e:.0e} ({'~' if m[2] else ''}{m[0] / m[1]:.3g}x faster: "
                               f"{fmt_t(m[1])} s vs kifmm {fmt_t(m[0])} s")
                        if same:
                            if c == "direct":
                                tc = min(r["t_eval"] for r in same)
                            else:
                                tc, _ = time_at(same, e)
                            if tc:
                                q = m[0] / tc
                                txt += (f"; re-measured with the kifmm runs: {fmt_t(tc)} s, "
                                        + (f"{q:.3g}x faster" if q >= 1 else
                                           f"kifmm {1 / q:.3g}x faster"))
                        es.append(txt + ")")
                if es:
                    items.append(f"{'the direct sum' if c == 'direct' else c} at " +
                                 ", ".join(es))
            if items:
                lines.append(f"* {case}{' (periodic)' if is_periodic(recs, case) else ''}, "
                             f"N = {nlabel(n, runs[0]['natoms'])}: " + "; ".join(items) + ".")
    return ("\n".join(lines) + "\n") if lines else "(none in these results)\n"


def recheck_map(results_path):
    """(case, n, spec) -> the latest ok recheck record with a CPU time."""
    out = {}
    for r in side_records(results_path, r"recheck-.*\.jsonl"):
        if r.get("kind") == "recheck" and r.get("status") == "ok" and "c_eval" in r:
            k = (r.get("case"), r.get("n"), r.get("spec"))
            if k not in out or r.get("date", "") >= out[k].get("date", ""):
                out[k] = r
    return out


def remaining(cfg_path, profile, recs):
    """What the profile asks for that the results do not have (yet)."""
    try:
        with open(cfg_path) as f:
            cfg = json.load(f)
        cases = cfg["profiles"][profile]["cases"]
        mem_limit = cfg["profiles"][profile].get("limits", {}).get(
            "memory_limit_mb", cfg["limits"]["memory_limit_mb"])
    except (OSError, KeyError, json.JSONDecodeError):
        return []
    out = []
    for c in cases:
        if not c.get("enabled", True):
            continue
        name = c["name"]
        ns = c.get("n") or ["start", "end"]
        periodic = c.get("periodic", False) or name == "scene_platelets"
        fams = ["ewald", "pppm"] if periodic else ["msm"]
        for n in ns:
            tried = [r for r in recs if r.get("kind") == "run" and r.get("case") == name
                     and r.get("n") == n]
            if not any(r["solver"] == "kifmm" and r["status"] == "ok" for r in tried):
                out.append(f"`{name}` N = {n}: not measured (CPU-time campaign)")
                continue
            miss = [f for f in fams if not any(r["solver"] == f for r in tried)]
            if miss:
                out.append(f"`{name}` N = {n}: no {' / '.join(miss)} runs yet")
            latest = {}
            for r in tried:
                latest[r["spec"]] = r
            stop = [r["spec"] for r in latest.values()
                    if r["status"] in ("skipped", "timeout", "stopped")]
            if stop:
                out.append(f"`{name}` N = {n}: skipped or stopped for time (runs table says "
                           f"why): {', '.join(stop)}")
                # the same settings' peak memory at the largest smaller N, scaled as N: those
                # that would also exceed the memory limit of the campaign
                big = []
                for spec in stop:
                    ran = [r for r in recs if r.get("kind") == "run" and r.get("case") == name
                           and r.get("spec") == spec and r.get("status") == "ok"
                           and isinstance(r.get("n"), int) and isinstance(n, int)
                           and r["n"] < n and r.get("mem_mb")]
                    if ran:
                        r = max(ran, key=lambda x: x["n"])
                        mem = r["mem_mb"] * n / r["n"]
                        if mem > mem_limit:
                            big.append(f"{spec} ~{mem / 1000:.1f} GB")
                if big:
                    out.append(f"`{name}` N = {n}, of these: peak memory scaled as N from "
                               f"the largest smaller N above the {mem_limit / 1000:g} GB limit "
                               f"too: {', '.join(big)}")
                # a solver none of whose settings reached 1e-7 at the largest smaller N will
                # not fill the 1e-7 column here either
                for fam in sorted({sp.split(":")[0] for sp in stop} - {"kifmm"}):
                    ran = [r for r in recs if r.get("kind") == "run" and r.get("case") == name
                           and r.get("solver") == fam and r.get("status") == "ok"
                           and isinstance(r.get("n"), int) and isinstance(n, int)
                           and r["n"] < n and r.get("error") is not None]
                    if not ran:
                        continue
                    n0 = max(r["n"] for r in ran)
                    best = min((r for r in ran if r["n"] == n0), key=lambda x: x["error"])
                    if best["error"] > min(TARGETS):
                        out.append(f"`{name}` N = {n}: no {fam} setting reached "
                                   f"{min(TARGETS):.0e} at N = {n0} (best {best['error']:.1e}, "
                                   f"{best['spec']}): its {min(TARGETS):.0e} column is "
                                   "expected to stay n/r whichever of its settings runs here")
    return out


def pending_list(cfg_path, profile):
    try:
        with open(cfg_path) as f:
            cfg = json.load(f)
        cases = cfg["profiles"][profile]["cases"]
    except (OSError, KeyError, json.JSONDecodeError):
        return []
    return [(c["name"], c.get("pending", "disabled")) for c in cases
            if not c.get("enabled", True)]


def high_order_note(recs):
    """The tree depths of the P >= 12 runs with open boundaries (depth <= 1: all near field,
    a direct sum, error at round-off), and where their far field is tested."""
    byd = {}
    for case in cases_of(recs):
        for n in ns_of(recs, case):
            rs = [r for r in ok_runs(recs, case, n, "kifmm") if (r.get("order") or 0) >= 12
                  and not r.get("periodic") and r.get("depth") is not None]
            if rs:
                d = min(r["depth"] for r in rs)
                byd.setdefault(min(d, 2), []).append(f"{case} {nlabel(n, rs[0]['natoms'])}")
    if not byd:
        return ""
    words = {0: "a single leaf (depth 0)", 1: "depth 1 (8 adjacent leaves, no far field)",
             2: "depth >= 2 (far field)"}
    return ("With open boundaries the trees chosen for these orders have " +
            "; ".join(f"{words[d]} on {', '.join(v)}" for d, v in sorted(byd.items())) +
            ". Depth 0 or 1 is a direct sum (error at round-off), so the far field of these "
            "orders is tested at the larger N, the rows of the order table below.")


def scene_snapshot_note(recs, results_path):
    """The trees of kifmm on the 1000-atom charges-box, and which snapshots differ from those
    of results/scene-snapshots-COMMIT.jsonl (references and competitor runs on snapshots of
    an earlier version of the examples, kept apart)."""
    txt = ""
    cb = [r for r in ok_runs(recs, "scene_charges-box", solver="kifmm") if r.get("depth")
          is not None]
    if cb:
        ds = sorted({r["depth"] for r in cb})
        txt += (f"charges-box has {cb[0]['natoms']} atoms in the quick variant: kifmm's octree "
                "has depth " + "/".join(str(d) for d in ds) + " there (depth 0 or 1 with "
                "open boundaries: all near field, a direct sum). ")
    refs = {(r["case"], r["n"]): r for r in recs if r.get("kind") == "reference"}
    d = os.path.dirname(os.path.abspath(results_path))
    try:
        files = sorted(f for f in os.listdir(d) if re.fullmatch(r"scene-snapshots-.*\.jsonl", f))
    except OSError:
        files = []
    newest = {f: max((r.get("date", "") for r in side_records(results_path, re.escape(f))),
                     default="") for f in files}
    def rerun_note(keys):
        miss = [f"{c} {n}" for c, n in keys
                if not any(r.get("kind") == "run" and r.get("case") == c and r.get("n") == n
                           and r.get("solver") != "kifmm" for r in recs)]
        if not miss:
            return "; every solver ran on the current ones"
        return ("; on the current ones only kifmm ran: " +
                ", ".join(miss) + " (see [Pending](#pending))")
    for fn in sorted(files, key=lambda f: newest[f], reverse=True):
        old = [r for r in side_records(results_path, re.escape(fn))
               if r.get("kind") == "reference"]
        diff, same = [], []
        for o in old:
            r = refs.get((o["case"], o["n"]))
            if r is None:
                continue
            if same_atoms(r, o):
                same.append(o)
            else:
                rel = (abs(r["f_rms"] - o["f_rms"]) / abs(o["f_rms"])
                       if r.get("natoms") == o.get("natoms") and o.get("f_rms") else None)
                diff.append((o, rel))
        rels = sorted(x for _, x in diff if x is not None)
        commit = fn[len("scene-snapshots-"):-len(".jsonl")]
        txt += (f"results/{fn} (commit {commit}) holds references and competitor runs on "
                f"snapshots of an earlier version of the examples; of its snapshots " +
                ", ".join(f"{o['case']} {o['n']}" + ("" if x is not None else
                                                      f" ({o['natoms']} atoms, now "
                                                      f"{refs[(o['case'], o['n'])]['natoms']})")
                          for o, x in diff) +
                (f" (relative change of the RMS reference force {rels[0]:.1e} - "
                 f"{rels[-1]:.1e})" if rels else "") +
                " are other atoms than the current ones, and its runs are not used in this "
                "report" + rerun_note([(o["case"], o["n"]) for o, _ in diff]) +
                ". ")
    if files:
        txt += ("The end states depend on the engine (the scenes run with kifmm, whose forces "
                "differ within the requested accuracy from one tree to another). ")
    sc = sorted({str(r.get("commit")) for (c, _), r in refs.items() if c.startswith("scene_")})
    if sc:
        txt += ("The current snapshots and their references were made at commit " +
                ", ".join(sc) + ".")
    return txt


def timing_paragraph(recs, results_path):
    """The summary's paragraph on when the kifmm runs, the references and the competitor runs
    were measured, and the CPU-time factor between those times."""
    kc = kifmm_commit(recs)
    fn = retime_factor(recs, results_path, kc)
    fk = retime_factor(recs, results_path, kc, "kifmm")
    refs = [r for r in recs if r.get("kind") == "reference"]
    comp = [r for r in ok_runs(recs) if r["solver"] != "kifmm"]
    same = sorted({r["case"] for r in comp if r.get("commit") == kc})
    others = sorted({str(r.get("commit")) for r in comp if r.get("commit") != kc})
    if not others:
        return (f"All runs of these results were measured together (commit {kc}): the ratios "
                "compare CPU times measured at the same time.\n")
    subj = [f"The kifmm runs (engine at {kc})"]
    if refs and all(r.get("commit") == kc for r in refs):
        subj.append("the exact references")
    if same:
        subj.append("the competitors' runs on " + ", ".join(same))
    txt = (", ".join(subj[:-1]) + " and " + subj[-1] if len(subj) > 1 else subj[0]) + (
        " were measured after the other competitor runs (commits " + ", ".join(others) + "). ")
    if fn:
        txt += (f"Measured again at the time of the kifmm runs, the stored competitors' "
                f"settings took a median {fn[0]:.2f}x their stored CPU time ({fn[1]:.2f} - "
                f"{fn[2]:.2f}, {fn[3]} settings)" +
                (f", kifmm's own runs {fk[0]:.2f}x ({fk[1]:.2f} - {fk[2]:.2f})" if fk else "") +
                " (table under [Settings of this run](#settings-of-this-run)). ")
        if abs(fn[0] - 1) >= 0.05:
            txt += ("The ratios against stored competitor runs therefore " +
                    ("understate" if fn[0] > 1 else "overstate") +
                    " kifmm's advantage by about that factor; ")
        else:
            txt += "CPU times measured at the two times agree to within 5 % in the median; "
        txt += ("where every run of a competitor at that N was measured again, that ratio is "
                "given in parentheses. ")
    else:
        txt += ("No stored competitor setting was measured again at the time of the kifmm "
                "runs: the ratios compare CPU times measured at different times (other "
                "re-measurements: table under [Settings of this run](#settings-of-this-run)). ")
    big = [r for r in refs if r.get("c_direct_sum") and 0 < r.get("sampled", 0) < r["natoms"]]
    if big:
        rc = sorted({str(r.get("commit")) for r in big})
        txt += ("The direct sums of the 1e6 rows (`(s)`) were timed on the sample when the "
                "references were made" + (", with the kifmm runs." if rc == [kc] else
                                          f" (commit {', '.join(rc)}).") )
    return txt + "\n"


def small_n_note(recs, results_path, rechecks):
    """N ~ 1e3 (at most 2500 atoms): the depths of kifmm's trees, kifmm's time against the
    direct sum re-measured at the same time, and against the newest archived engine."""
    kc = kifmm_commit(recs)
    small = [r for r in ok_runs(recs, solver="kifmm")
             if r["natoms"] <= 2500 and r.get("depth") is not None]
    if not small:
        return ""
    parts = []
    for per, word in ((False, "open boundaries"), (True, "periodic boundaries")):
        rs = [r for r in small if bool(r.get("periodic")) == per]
        if not rs:
            continue
        byd = {}
        for r in rs:
            byd.setdefault(r["depth"], []).append(r)
        main_d = max(byd, key=lambda d: len(byd[d]))
        items = []
        for d in sorted(byd):
            v = byd[d]
            it = f"depth {d} in {len(v)}"
            if d != main_d and len(v) <= 8:
                it += " (" + ", ".join(f"{r['case']} {nlabel(r['n'], r['natoms'])} "
                                       f"P={r.get('order')}"
                                       for r in sorted(v, key=lambda x: (x["case"], nkey(x["n"]),
                                                       x.get("order") or 0))) + ")"
            items.append(it)
        parts.append(", ".join(items) + f" of {len(rs)} settings with {word}")
    txt = ("At N ~ 1e3 (at most 2500 atoms) the trees that kspace kifmm chooses from the atom "
           "positions at the first evaluation (kifmm::choose_tree) have " + "; ".join(parts) +
           "; with open boundaries depth 0 or 1 is all near field (a direct sum in one or 8 "
           "leaves, exact to round-off). ")
    # kifmm against kifmm::direct_sum re-measured at the time of the kifmm runs
    q = []
    for (case, n, spec), x in sorted(rechecks.items(), key=str):
        if spec != "direct" or x.get("commit") != kc:
            continue
        ks = ok_runs(recs, case, n, "kifmm")
        if not ks or ks[0]["natoms"] > 2500:
            continue
        tk, _ = time_at(ks, 1e-7)
        if tk:
            q.append((tk / x["c_eval"], f"{case} {nlabel(n, ks[0]['natoms'])}"))
    if q:
        txt += ("kifmm's CPU time at 1e-7 over that of kifmm::direct_sum re-measured with the "
                "kifmm runs: " + ", ".join(f"{lab} {v:.2f}" for v, lab in q) + ". ")
    arch = archives(results_path)
    if arch:
        old = archived_runs(results_path, arch[0])
        v = sorted(r["t_eval"] / old[(r["case"], r["n"], r["spec"])]["c_eval"]
                   for r in small if (r["case"], r["n"], r["spec"]) in old
                   and same_atoms(r, old[(r["case"], r["n"], r["spec"])]))
        if v:
            txt += (f"Against the archived runs of {arch[0][len('kifmm-'):-len('.jsonl')]} on "
                    f"the same atoms there, CPU eval new / old is a median {median(v):.2f} "
                    f"({v[0]:.2f} - {v[-1]:.2f}, {len(v)} settings; [comparison with the "
                    "archived runs](#kifmm-runs-of-earlier-engine-commits)).")
    return txt


def write_doc(recs, doc, plots, profile, cases_path, results_path, page=None):
    """The full tables (every run, settings, references, setup, provenance) into doc; page:
    the user page that summarizes them, if one is written."""
    d = os.path.dirname(os.path.abspath(doc))
    rel = {k: os.path.relpath(v, d) for k, v in plots.items()}
    cases = cases_of(recs)
    main_cases = [c for c in cases if not any(r.get("hard") and r["case"] == c
                                              for r in recs if r.get("kind") == "run")]
    hard_cases = [c for c in cases if c not in main_cases]
    out = []
    w = out.append
    w("# Speed versus error, full tables: kspace kifmm, LAMMPS msm, ewald, pppm and direct "
      "summation\n")
    w("<!-- generated by bench/solvers/report.py from bench/solvers/results/*.jsonl; "
      "edit report.py, not this file -->\n")
    w(f"Profile `{profile}`." + (f" Summary: [{os.path.relpath(page, d)}]"
                                 f"({os.path.relpath(page, d)})." if page else "") +
      " Reproduce with one command (hours on one core; resumable, runs already in the "
      "results file are kept):\n")
    w("```sh\nbash bench/solvers/run.sh            # full: bench/solvers/results/ + doc/benchmarks.md\n"
      "bash bench/solvers/run.sh --quick    # N <= 1e4, minutes, report in the build directory\n"
      "bash bench/solvers/run.sh --report-only   # tables and plots from the stored results\n"
      "bash bench/solvers/run.sh --solvers kifmm # kifmm only (new engine; see run.sh)\n```\n")
    w("## Summary: kifmm's speed ratio at matched error (largest N of each case)\n")
    w("How many times faster kifmm is than the best setting of each LAMMPS solver (msm for "
      "open boundaries; ewald and pppm for periodic ones) and than the exact direct sum, for "
      "the same measured relative force error (below 1x kifmm is slower; `~`: one of the "
      "times is a bound or an N^2 extrapolation, see below; `msm n/r`: no run of that solver "
      "reached that error). Full tables: [speed ratio at matched error]"
      "(#speed-ratio-at-matched-error).\n")
    w(timing_paragraph(recs, results_path))
    w(summary(recs, cases_of(recs), recheck_map(results_path)))
    w("\n## Where kifmm is slower\n")
    fn = retime_factor(recs, results_path, kifmm_commit(recs))
    w("Every case, N and matched error where another solver needs less CPU time than kifmm "
      "for the same measured error (`~`: one time is a bound or an extrapolation), and where "
      "the competitor's runs were measured again at the time of the kifmm runs, the ratio "
      "then" + ((" (the stored competitor runs took " + ("less" if fn[0] > 1 else "more") +
                 " CPU time than when measured again, see [Settings of this run]"
                 "(#settings-of-this-run))") if fn else "") +
      ". " + small_n_note(recs, results_path, recheck_map(results_path)) + "\n")
    w(losses(recs, cases_of(recs), recheck_map(results_path)))
    w("## What is measured\n")
    w("""All solvers see the same atoms (one LAMMPS data file per configuration and N, `units lj`,
unit charges, dielectric 1, `boundary f f f`) and are compared with the same exact
reference (the same data and reference files for every solver), measured by the driver
(`bench/solvers/run_bench.py` calling `bench_solvers`, one child process per solver run).
kifmm's runs and the competitors' were measured at different times (commits and dates in
[Settings of this run](#settings-of-this-run)); the times are CPU times, which stay
comparable between runs made hours apart:

* **error**: the relative RMS error of the **total** force on the atoms,
  `||F - F_exact|| / ||F_exact||` (sums over atoms and components). For msm the total force
  is pair coul/msm + kspace msm, the forces the atoms feel. `F_exact` is the direct sum by
  `kifmm::direct_sum` on every atom for N <= 120000; above that (the 1e6 runs) it is computed
  on a random sample of 4000 atoms (whole clumps for clump configurations; **sampled
  reference**, marked in the plots) and the error is the sample's mean squared error over
  the mean squared force of **all** atoms, `sqrt(sum_sample |F - F_exact|^2 / n_sample) /
  F_rms`. `F_rms`, the RMS force over all atoms, is computed with the reference by the kifmm
  engine at order 12 on all atoms (its relative error on the sample is in the reference
  record, `f_rms_all_sample_error`, about 1e-10; an error in `F_rms` would scale every
  solver's error alike; each run also records the RMS of its own forces, `f_rms_all_solver`).
  The sample's own ratio would overstate the errors: on random atoms the squared force is
  dominated by the few closest pairs, which a sample mostly misses, so the sample's RMS
  force is small (0.61 of all atoms' on 4000 of 1e5 uniform atoms). This is the measure of
  kifmm's own check (doc/kspace_kifmm.rst, close pairs). Runs recorded before the
  references held `F_rms` are rescaled by (RMS force of the sample) / `F_rms`
  (`error_denominator` says which; the sample's own ratio stays as `error_sample`).
  The reference was checked against LAMMPS's own direct sum (pair coul/cut with a cutoff
  beyond the box, solver `coulcut`): they agree to ~1e-15 where both ran.
* **eval**: time per force evaluation after setup: `pair->compute(0,0)` plus
  `kspace->compute(0,0)` called directly (forces only, no energy/virial, no neighbor list
  rebuild: atoms do not move), **median** of at least 3 evaluations and at least 1 s. The
  time is the **CPU time of the process** (`CLOCK_PROCESS_CPUTIME_ID`; every solver runs on
  one thread, so this is the core time the evaluation needs): the host's cores also ran
  other work (load average below), which inflates wall times by factors up to ~5 depending
  on the moment, while CPU times stay comparable between runs made minutes or hours apart.
  The wall times (MPI_Wtime) are in results.jsonl as `t_eval` (`c_eval` is the CPU time).
  `pair / kspace` splits the CPU time. bench/solvers/results/wall-clock-v1.jsonl holds runs
  with wall times only; **none of its times is used in this report** (no ratio mixes
  wall-clock and CPU times).
* **setup**: CPU time (the wall time is in results.jsonl as `t_setup`) of the first
  `run 0 post no` (init, neighbor lists, grid or operator setup and the first evaluation
  including energy and virial; kifmm in a periodic box computes the virial on a
  single-level grid, which on clustered atoms costs many evaluations of its octree: the
  setup times of plummer_periodic). kifmm reads its translation operators
  from a warm disk cache (filled by the `setup` step of the campaign); the cold precompute
  per order is in the operator setup table.
* **memory**: peak resident memory of the solver: `/proc/self/status` VmHWM after the
  evaluations minus VmRSS after `read_data` (VmHWM is reset through
  `/proc/self/clear_refs` after read_data). Each solver runs in its own child process, so
  the peak is its own.
* kifmm: `pair_style none`, `kspace_style kifmm ACC` (order from the calibration table of
  the boundary) or `kspace_modify kifmm order P` for explicit orders (`P=` in the tables).
  The leaf size is chosen at the first evaluation of each run from the atom positions
  (one rank: kifmm::choose_tree(kernel, options, n, xyz) builds the octree of the atoms for a
  few candidate leaf sizes and keeps the one of least modelled cost), then tuned by timing
  (`kspace_modify kifmm tune`, default yes: the first evaluations of a run time neighbouring
  trees and keep the fastest). The timed evaluations come after the tuning and after the
  error measurement of the tree kept, so **eval** is the time of the tree kifmm runs with;
  those evaluations are counted in results.jsonl as `tune_evaluations` (wall time `t_tune`).
  The tree depth of each run is `depth` in results.jsonl.
* msm: `pair_style coul/msm C*s` (s = mean atom spacing of the box, `(V/N)^(1/3)`),
  `pair_modify table 0`, `kspace_style msm A*F_rms`, `kspace_modify cutoff/adjust no` and
  optionally `order`. LAMMPS's msm accuracy is absolute (relative to the force between two
  unit charges at unit distance); multiplying by the reference's RMS force makes A the
  requested relative error. Several (C, A, order) are run and the Pareto front is used: the
  comparison is against msm's best setting for each error, not against one guess.
* direct: `kifmm::direct_sum` (vectorized O(N^2), the same code as the reference) on all
  atoms, up to N = 120000; LAMMPS pair coul/cut (O(N^2) neighbor list) up to N = 12000.
  Above N = 120000 (the 1e6 runs) the direct sum is **timed on the sample** of the reference
  (all N sources, the 4000 sampled targets, CPU time) and scaled by N / 4000 (exact for a
  sum whose cost is N targets x N sources): marked `(s)`.
* Competitors at N >= 5e4 (msm, ewald, pppm) run only the settings that were on that
  solver's Pareto front at the previous N of the case; a setting whose predicted CPU time
  (from the largest smaller N where it ran, scaled as N; as N^2 for direct sums and as
  N^2.25 for ewald, whose k vectors grow as N with a cutoff of a fixed number of spacings:
  161x and 173x measured from 1e4 to 1e5; the setup and 3 more evaluations) exceeds the
  per-run limit of 600 s CPU is recorded as skipped, not run; a run is stopped at 600 s CPU
  (or 2400 s wall) and recorded as timeout (other limits: `cpu_limit_s` in results.jsonl,
  listed below). Some `skipped` records were judged with a simpler predictor (N^2, or
  N^1.5 from wall times, for ewald); the driver judges skipped settings again, so the
  `skipped` rows that remain are its final judgement. At N >= 5e5
  (the 1e6 runs; limits.large_n) the campaign runs kifmm at acc 1e-2, 1e-3, 1e-5, 1e-7
  only (enough to bracket the matched errors; the explicit orders are shown up to 1e5) and
  stops or skips any run above 300 s CPU, to bound the campaign's time. When every
  kept setting of a competitor fails at some N (memory, in the clustered cases at 1e5),
  its other settings are not tried at that N; at the next N all its settings are tried
  again (those that failed at a smaller N are skipped).
* **periodic cases** (`boundary p p p`, the unit cube as the cell, same configurations):
  kifmm (periodic mode of the style) against LAMMPS `ewald` and `pppm` with
  `pair_style coul/long C*s` (`pair_modify table 0`, accuracy A*F_rms as for msm; pppm
  optionally `kspace_modify order`). The exact reference is `kifmm::periodic_direct_sum`:
  an Ewald sum with libm's erfc at double accuracy (tin-foil boundary conditions, as ewald and
  pppm), on all atoms up to N = 12000 and on 2000 sampled atoms above (the error divided by
  the RMS force of all atoms, as for open boundaries). It is not LAMMPS's
  `ewald 1e-12`: pair coul/long evaluates erfc with a polynomial of error ~1e-7, so LAMMPS's
  ewald at 1e-12 agrees with the exact sum only to 7.7e-8 (measured on 4000 uniform atoms),
  which is also the floor of ewald and pppm in these tables. The exact solver of the periodic
  cases (`direct`) is that Ewald sum itself (O(N^2) real space), up to N = 5000.
* Timings are noisy (other work on the host, see the load average below): the report
  compares solvers through **ratios of times measured in the same campaign**, never across
  machines.
""")
    lim = limit_runs(recs)
    if lim:
        w("Runs with a per-run CPU limit other than the profile's (`run_bench.py --timeout`): "
          + lim + "\n")
    w("## Settings of this run\n")
    w(settings_table(recs, results_path))
    rt = recheck_table(recs, results_path)
    if rt:
        w("\nHow well CPU times measured hours apart agree: settings of the campaign measured "
          "again at the end of a kifmm remeasurement (same command, data and reference; "
          "results/recheck-*.jsonl, used elsewhere only for the re-measured ratios in [Where "
          "kifmm is slower](#where-kifmm-is-slower)). The spread is the uncertainty of a "
          "ratio between the kifmm and the competitor runs, which were measured at different "
          "times. " + recheck_summary(recs, results_path) + "\n\n")
        w(rt)
    w("\n## Speed ratio at matched error\n")
    w("""Time of kifmm at the error E and how many times longer each other solver takes for the
same measured error (larger = kifmm faster; `-`: solver not run on that case; `failed`: every
setting of that solver failed, see the runs tables). Each solver's
time at E is interpolated linearly in log(time)-log(error) between the two points of its
Pareto front around E; `<=`: the solver's fastest run is already more accurate than E (its
time is an upper bound, and a ratio built from it is marked `~`); `n/r`: no run of that
solver reached E (or all its settings failed: see the runs tables); `~` on direct (open
boundaries): its time is extrapolated as N^2 from the largest N where it ran. For periodic
cases `direct` is the exact Ewald sum, run at N <= 5000 only.
""")
    allc = main_cases + hard_cases
    open_c = [c for c in allc if not is_periodic(recs, c)]
    per_c = [c for c in allc if is_periodic(recs, c)]
    if open_c:
        w("\n### Open boundaries (boundary f f f)\n")
        w(ratio_table(recs, open_c))
    if per_c:
        w("\n### Periodic boundaries (boundary p p p, unit cube)\n")
        w(ratio_table(recs, per_c))
    if "time_vs_n" in rel:
        w(f"\n![time per evaluation versus N at matched error]({rel['time_vs_n']})\n")
    w("\n## kifmm scaling with N at fixed error\n")
    sd = sorted({r["depth"] for r in ok_runs(recs, solver="kifmm") if r["natoms"] <= 2500
                 and not r.get("periodic") and r.get("depth") is not None})
    w("Least-squares exponent k of time ~ N^k over the N >= 5000 of each case (1 = O(N)); "
      "at N ~ 1000 the octree of kifmm is small" +
      (f" (depth {sd[0]}" + (f" - {sd[-1]}" if len(sd) > 1 else "") + " with open "
       "boundaries; depth 0 or 1 is all near field, a direct sum)" if sd else "") +
      ", so those N are left out of the fit.\n")
    w(scaling_table(recs, main_cases + hard_cases))
    w("\n## Hard cases\n")
    w("""* **dipole3**: neutral rigid clumps of 3 pebbles with charges -1, 0, +1 (the middle pebble
  has zero charge: it is neither source nor target for kifmm; potentials/dipole3.mol, spacing
  0.01, scaled down at high N so that clumps do not overlap). The force on each pebble is
  dominated by its clump partner, but that part cancels in the clump's net force, which is
  what moves a rigid clump: the **clump net-force error** is
  `||sum_clump (F - F_exact)|| / ||sum_clump F_exact||` over whole sampled clumps, relative to
  the small net forces.
* **platelets**: rigid bodies of 1094 pebbles, two HCP layers of opposite charge
  (potentials/platelet_n14.mol from tools/clump_shapes.py), 1, 8 and 64 bodies at random
  orientations: near-cancelling double layers; same net-force error per body (not for the
  single platelet, N = 1094, whose net force is zero by the third law).
* **collapse**: a Plummer sphere 10 times more concentrated (scale radius 0.005 in the unit
  box) as a stand-in for the end state of a gravitational collapse.
* **highest orders**: kifmm at P = 12 and 14 (explicit `order`) on every case: the error must
  keep falling. """ + high_order_note(recs) + """
* **scene snapshots** (`scene_*`, N shown with the state): the start and end states of the
  four example scenes (charges-box, dipoles, gravity-collapse, platelets), quick variants,
  made by bench/solvers/scene_snapshots.py, which runs a copy of each example with two added
  `write_dump` lines (after the `run 0` that starts the production run, and at the end).
  Charges are the scenes' q (gravity-collapse: the masses, as charges; the relative error of
  the same linear sum does not depend on the sign), dielectric 1; platelets is periodic
  (boundary p p p), the others open. Clump net-force errors for dipoles (3 pebbles) and
  platelets (182 pebbles per platelet in the quick variant). charges-box and
  gravity-collapse carry charges of one sign: LAMMPS's msm stops on them ("System is not
  charge neutral"), so only kifmm and the direct sums run there. """ +
      scene_snapshot_note(recs, results_path) + "\n")
    w(hard_table(recs, hard_cases))
    crt = clump_ratio_table(recs, hard_cases)
    if crt:
        w("\nMatched error on the clump net forces (same interpolation as above, on the clump "
          "net-force error):\n\n")
        w(crt)
    w("\n### Error versus kifmm order (each case at its largest N with explicit orders)\n")
    w(order_table(recs, main_cases + hard_cases))
    if "error_vs_order" in rel:
        w(f"\n![kifmm error versus order]({rel['error_vs_order']})\n")
    w("\n### kifmm's error against the requested accuracy\n")
    w("Every kifmm run at `acc=A`: its measured error (as above) over A. The order search "
      "takes the lowest order whose error measured on the atoms meets A (doc/kspace_kifmm.rst); "
      "errors far below A come from trees that are a direct sum (N ~ 1e3), from the order "
      "below having missed A, or from the bound that decides between two orders (the RMS "
      "difference of their forces plus the higher order's error) having exceeded A while the "
      "lower order's own error met it (last column: the runs of the same case and N at the "
      "order below, on the same tree, error / A in parentheses; the run logs list the orders "
      "tried).\n\n")
    w(accuracy_table(recs, main_cases + hard_cases))
    w("\n### kifmm operator setup per order\n")
    w(setup_table(recs))
    ects = [(fn, engine_change_table(recs, results_path, fn)) for fn in archives(results_path)]
    ects = [(fn, t) for fn, t in ects if t]
    if ects:
        w("\n### kifmm runs of earlier engine commits\n")
        w("The same kifmm settings on the same atoms and reference, measured on the engine of "
          "this report and on an earlier engine whose runs are archived (not used anywhere "
          "else in this report): ratio of the CPU times per evaluation (below 1: the current "
          "engine is faster) and of the measured errors (the calibration table and tree "
          "choice are the engine's own at each commit). The archived times were measured "
          "at other times; the re-measured settings above show how far CPU times measured "
          "at different times agree.\n")
        for fn, t in ects:
            dcs = depth_change_summary(recs, results_path, fn)
            w(f"\nAgainst bench/solvers/results/{fn} (engine at "
              f"{fn[len('kifmm-'):-len('.jsonl')]})." +
              archive_timing_note(recs, results_path, fn) + (" " + dcs if dcs else "") +
              "\n\n")
            w(t)
    w("\n## Pareto fronts (error versus time) per configuration\n")
    w("Filled markers: relative force error of the atoms; hollow markers: clump net-force "
      "error. Lines join each solver's Pareto front. Dashed vertical lines: the exact direct "
      "sums (error at round-off). Errors below 1e-16 (kifmm runs whose octree is a single "
      "leaf, i.e. a direct sum) are drawn at 1e-16. Dotted lines: 1e-3, 1e-5, 1e-7.\n")
    for c in main_cases + hard_cases:
        if f"pareto_{c}" in rel:
            w(f"\n![{c}]({rel[f'pareto_{c}']})\n")
    w("\n## All runs\n")
    for c in main_cases + hard_cases:
        w(f"\n### {c}\n")
        w(runs_table(recs, c))
    w("\n### Exact references\n")
    w(reference_table(recs, main_cases + hard_cases))
    w("\n## Pending\n")
    rem = remaining(cases_path, profile, recs)
    if rem:
        w("Asked for by profile `" + profile + "` of cases.json and not in these results "
          "(`bash bench/solvers/run.sh` resumes the campaign and runs exactly these):\n")
        w("".join(f"* {x}\n" for x in rem))
    if SKIPPED_WALL:
        w(f"* {len(SKIPPED_WALL)} runs in the results file have wall times only (an older "
          "binary): left out of this report.\n")
    pend = pending_list(cases_path, profile)
    w("""* **Full-size scene snapshots**: the scene cases use the quick variants of the examples
  (1000 to 6000 atoms); the full-size scenes (10^4 to 10^5 atoms, 10^5 steps) take hours
  each. `"full": true` in a `scene_*` case of bench/solvers/cases.json makes
  scene_snapshots.py run the full variant (delete the case's snapshots in the work directory
  first). The generated cases (`collapse`, `platelets`, `dipole3`) cover those sizes.
""")
    for name, why in pend:
        w(f"* case `{name}` of profile `{profile}` disabled: {why}\n")
    with open(doc, "w") as f:
        f.write("\n".join(x.rstrip("\n") + "\n" for x in out).replace("\n\n\n", "\n\n"))


# ----------------------------------------------------------------------------- user page

CASE_WORDS = {
    "uniform": "uniform random in the unit cube, charges +-1",
    "plummer": "Plummer sphere (scale radius 0.05), charges +-1",
    "clusters": "two dense balls (radius 0.02) near opposite corners",
    "dipole3": "rigid 3-pebble dipole clumps (charges -1, 0, +1; clump net-force error too)",
    "collapse": "Plummer sphere of scale radius 0.005 (a collapsed cloud)",
    "platelets": "platelets of 1094 pebbles in two oppositely charged layers",
    "uniform_periodic": "as uniform, periodic unit cell",
    "plummer_periodic": "as plummer, periodic unit cell",
    "dipole3_periodic": "as dipole3, periodic unit cell",
}
# the plots of the user page, in this order (those that exist)
PAGE_PLOTS = (("time_vs_n", "CPU time per evaluation against N at matched error (kifmm, the "
               "LAMMPS solvers and the direct sum; hollow markers: upper bounds)"),
              ("pareto_uniform_periodic", "error against CPU time of every run (lines: Pareto "
               "fronts), uniform charges with periodic boundaries: kifmm, ewald, pppm"),
              ("pareto_platelets", "error against CPU time of every run, charged platelets "
               "(filled: atom forces, hollow: net forces of the platelets; dashed: direct sums)"),
              ("error_vs_order", "kifmm's error against its order P, each case at its largest N "
               "with explicit orders"))


def fmt_pow(n):
    """1e3-style label of an atom count (its power of ten, rounded)."""
    return f"1e{round(math.log10(n))}" if n > 0 else "0"


def failed_reason(recs, case, n, c):
    """'all K settings failed (reasons)' when every run of solver c at (case, n) failed."""
    rs = [r for r in recs if r.get("kind") == "run" and r["case"] == case and r["n"] == n
          and r.get("solver") == c]
    if not rs or any(r["status"] == "ok" for r in rs):
        return None
    why = set()
    for r in rs:
        m = re.search(r"ERROR(?: on proc \d+)?: ([^,(]*)", r.get("message", ""))
        why.add(m.group(1).strip() if m else (
            f"skipped: {r.get('message', '')}" if r["status"] == "skipped" else r["status"]))
    return f"all {len(rs)} settings failed ({'; '.join(sorted(why))})"


def best_lammps(recs, case, n, e):
    """(ratio, solver, approximate) of the LAMMPS solver that is fastest at error e, or None
    when none reached e (or kifmm did not)."""
    best = None
    for c in COMPETITORS:
        m = matched(recs, case, n, c, e) if ok_runs(recs, case, n, c) else None
        if m and (best is None or m[1] / m[0] < best[0]):
            best = (m[1] / m[0], c, m[2])
    return best


def summary_table(recs, cases):
    """The page's table: one row per case at its largest N, kifmm's speed ratio at matched
    error against the direct sum and against the fastest LAMMPS solver (at the largest N
    where one ran), and notes on the LAMMPS solvers that failed or did not run."""
    hdr = ("| case | boundary | N | kifmm CPU s at 1e-05 | direct / kifmm: 1e-03 | 1e-05 | 1e-07 "
           "| LAMMPS solver / kifmm: 1e-03 | 1e-05 | 1e-07 | N of the LAMMPS comparison |")
    lines = [hdr, "|---|---|---|---|---|---|---|---|---|---|---|"]
    notes = []
    for case in cases:
        ns = [n for n in ns_of(recs, case) if ok_runs(recs, case, n, "kifmm")]
        if not ns:
            continue
        n = ns[-1]
        natoms = ok_runs(recs, case, n)[0]["natoms"]
        ref = ref_of(recs, case, n)
        samp = "*" if ref and ref["sampled"] < ref["natoms"] else ""
        tk, fk = time_at(ok_runs(recs, case, n, "kifmm"), 1e-5)
        row = (f"| {case} | {'periodic' if is_periodic(recs, case) else 'open'} | "
               f"{nlabel(n, natoms)}{samp} | {fmt_t(tk, fk)} |")
        td, fd = direct_time(recs, case, n)
        for e in TARGETS:
            tk, fk = time_at(ok_runs(recs, case, n, "kifmm"), e)
            if td is None or tk is None:
                row += " - |" if td is None else " n/r |"
                continue
            row += " " + fmt_ratio(ratio(td, tk), "~" if (fd == "~" or fk == "<=") else
                                   ("s" if fd == "s" else "")) + " |"
        ran = [c for c in COMPETITORS if any(r.get("kind") == "run" and r["case"] == case
                                             and r.get("solver") == c for r in recs)]
        nl = [m for m in ns if any(ok_runs(recs, case, m, c) for c in ran)]
        if nl:
            m = nl[-1]
            for e in TARGETS:
                b = best_lammps(recs, case, m, e)
                row += (f" {fmt_ratio(b[0], '~' if b[2] else '')} {b[1]} |" if b else " n/r |")
            row += f" {nlabel(m, ok_runs(recs, case, m)[0]['natoms'])} |"
        else:
            row += " - | - | - | - |"
        lines.append(row)
        mine = []
        for c in ran:
            why = failed_reason(recs, case, n, c)
            if why:
                mine.append(f"{c} at N = {nlabel(n, natoms)}: {why}")
            elif not any(r.get("kind") == "run" and r["case"] == case and r["n"] == n
                         and r.get("solver") == c for r in recs):
                mine.append(f"{c} not run at N = {nlabel(n, natoms)}")
            if nl and ok_runs(recs, case, nl[-1], c):
                continue
            for m in [x for x in ns if x != n]:
                why = failed_reason(recs, case, m, c)
                if why:
                    mine.append(f"{c} at N = {nlabel(m, ok_runs(recs, case, m)[0]['natoms'])}: "
                                f"{why}")
        if mine:
            notes.append(f"{case}: " + "; ".join(mine))
    return "\n".join(lines) + "\n", notes


def loss_list(recs, cases, rechecks):
    """Where another solver needs less CPU time than kifmm at matched error: one line per
    case, solver and N."""
    lines = []
    for case in cases:
        for n in ns_of(recs, case):
            runs = ok_runs(recs, case, n)
            if not runs:
                continue
            for c in list(COMPETITORS) + ["direct"]:
                got = []
                for e in TARGETS:
                    m = matched(recs, case, n, c, e)
                    if m and m[1] < m[0]:
                        got.append((e, m[0] / m[1], m[2], m[0]))
                if not got:
                    continue
                who = "the direct sum" if c == "direct" else c
                facs = {f"{'~' if g[2] else ''}{g[1]:.2f}x" for g in got}
                if len(facs) == 1:
                    txt = (f"{who} is {facs.pop()} faster at " +
                           ", ".join(f"{g[0]:.0e}" for g in got))
                else:
                    txt = f"{who} is faster: " + ", ".join(
                        f"{'~' if g[2] else ''}{g[1]:.2f}x at {g[0]:.0e}" for g in got)
                same = retimed_runs(recs, rechecks, case, n, c)
                if same:
                    e, tk = got[0][0], got[0][3]
                    tc = (min(r["t_eval"] for r in same) if c == "direct"
                          else time_at(same, e)[0])
                    if tc:
                        q = tk / tc
                        txt += (f" (measured again at the time of the kifmm runs: " +
                                (f"{q:.2f}x faster)" if q >= 1 else f"kifmm {1 / q:.2f}x faster)"))
                lines.append(f"* {case}{' (periodic)' if is_periodic(recs, case) else ''}, "
                             f"N = {nlabel(n, runs[0]['natoms'])}: {txt}.")
    return ("\n".join(lines) + "\n") if lines else "(none in these results)\n"


def small_n_depths(recs):
    """(open settings at N <= 2500, of which a tree of depth <= 1) for kifmm's runs."""
    rs = [r for r in ok_runs(recs, solver="kifmm") if r["natoms"] <= 2500
          and not r.get("periodic") and r.get("depth") is not None]
    return len(rs), sum(1 for r in rs if r["depth"] <= 1)


def wrap_md(text, width=96):
    """Markdown with its long prose lines and list items wrapped (tables, code blocks,
    headings, images and comments are left as they are)."""
    out, code = [], False
    for line in text.split("\n"):
        if line.startswith("```"):
            code = not code
        if code or line.startswith(("```", "|", "#", "![", "<!--")) or len(line) <= width:
            out.append(line)
        elif line.startswith("* "):
            out.append(textwrap.fill(line, width, subsequent_indent="  ",
                                     break_on_hyphens=False, break_long_words=False))
        else:
            out.append(textwrap.fill(line, width, break_on_hyphens=False,
                                     break_long_words=False))
    return "\n".join(out)


def write_page(recs, doc, plots, profile, results_path, full_path):
    """The user page: what was compared and how, one summary table, a few plots, where kifmm
    is slower, how to reproduce; the full tables are in full_path."""
    d = os.path.dirname(os.path.abspath(doc))
    rel = {k: os.path.relpath(v, d) for k, v in plots.items()}
    full_rel = os.path.relpath(full_path, d)
    cases = cases_of(recs)
    main_cases = [c for c in cases if not any(r.get("hard") and r["case"] == c
                                              for r in recs if r.get("kind") == "run")]
    cases = main_cases + [c for c in cases if c not in main_cases]
    rechecks = recheck_map(results_path)
    nmax = max((r["natoms"] for r in ok_runs(recs)), default=0)
    nmin = min((r["natoms"] for r in ok_runs(recs)), default=0)
    out = []
    w = out.append
    w("# Speed versus error: kspace kifmm against the direct sum and LAMMPS's msm, ewald, "
      "pppm\n")
    w("<!-- generated by bench/solvers/report.py from bench/solvers/results/*.jsonl; edit "
      "report.py, not this file -->\n")
    w("## What was compared, and how\n")
    w("The long-range Coulomb forces on the same atoms (LAMMPS data files, `units lj`, "
      "dielectric 1) computed by `kspace_style kifmm`, by LAMMPS's `msm` (open boundaries, with "
      "`pair_style coul/msm`), `ewald` and `pppm` (periodic boundaries, with `pair_style "
      "coul/long`), and by the exact direct sum. The configurations, at N from "
      f"{fmt_pow(nmin)} to {fmt_pow(nmax)}:\n")
    items = [f"* `{c}`: {CASE_WORDS[c]}" for c in cases if c in CASE_WORDS]
    if any(c.startswith("scene_") for c in cases):
        items.append("* `scene_*`: the start and end states of the four example scenes (quick "
                     "variants; gravity-collapse with its masses as charges)")
    w("\n".join(items) + "\n")
    w("""
Each solver runs at several settings (kifmm: accuracy 1e-2 to 1e-9 and explicit orders; msm,
ewald, pppm: accuracy, pair cutoff and order), each on one thread in its own process. Per run:

* **error**: relative RMS error of the total force on the atoms, `||F - F_exact|| /
  ||F_exact||`, against the exact direct sum (periodic: an Ewald sum at double accuracy);
  for the largest N (marked `*`) on a random sample of atoms, relative to the RMS force of
  all atoms;
* **cost**: CPU time of one force evaluation after setup (median of at least 3; kifmm after
  the evaluations that tune its tree).

A solver's time at an error E is interpolated on its Pareto front (the runs that no other run
of the same solver beats in both time and error), so each solver is taken at its best setting
for that error. The **speed ratio** at E is the other solver's time divided by kifmm's: above
1x kifmm is faster.
""")
    w("## Summary: speed ratio at matched error\n")
    w("At each case's largest N. The LAMMPS column names the fastest of msm, ewald and pppm at "
      "that error, at the largest N where one of them ran. `n/r`: no setting reached that "
      "error; `-`: not run (periodic cases: the exact Ewald sum runs at small N only); `~`: "
      "one of the two times is an upper bound or an N^2 extrapolation; `(s)`: the direct sum "
      "timed on the sampled atoms and scaled by N / sample.\n")
    tab, notes = summary_table(recs, cases)
    w(tab)
    if notes:
        w("\nWhere a LAMMPS solver did not run or failed:\n\n" +
          "\n".join(f"* {x}" for x in notes) + "\n")
    fn = retime_factor(recs, results_path, kifmm_commit(recs))
    if fn:
        w(f"\nThe LAMMPS solvers' runs and kifmm's were measured at different times. "
          f"{fn[3]} of the LAMMPS and direct-sum settings, measured again at the time of the "
          f"kifmm runs, took {fn[1]:.2f} to {fn[2]:.2f} times (median {fn[0]:.2f}) their "
          "stored CPU time: that is the uncertainty of a ratio.\n")
    shown = [(k, cap) for k, cap in PAGE_PLOTS if k in rel]
    if not shown:
        shown = [(k, k) for k in sorted(rel)][:3]
    if shown:
        w("## Plots\n")
        for k, cap in shown:
            w(f"![{k}]({rel[k]})\n\n*{cap}.*\n")
    w(extra_sections())
    w("## Where kifmm is slower\n")
    w("Every case, N and error at which another solver needed less CPU time than kifmm:\n")
    w(loss_list(recs, cases, rechecks))
    tot, shallow = small_n_depths(recs)
    if tot:
        w(f"\nAt N <= 2500 with open boundaries kifmm's tree is a single leaf or 8 leaves in "
          f"{shallow} of {tot} settings: the evaluation is then a direct sum itself, and its "
          "time equals the direct sum's within the measurement spread.\n")
    w("## Reproduce\n")
    w("```sh\nbash bench/solvers/run.sh\n```\n")
    w("builds `bench_solvers` and `lmp_kifmm` in `build/`, measures what "
      "bench/solvers/results/results.jsonl does not hold yet (the full campaign takes hours on "
      "one core; it is resumable), and writes this page, the plots and the full tables. "
      "`--report-only` regenerates them from the stored results in seconds; `--quick` runs a "
      "reduced campaign (N <= 1e4, minutes) into the build directory.\n")
    w(f"All runs, settings, memory, setup costs, clump net-force errors, scaling exponents and "
      f"the provenance of the measurements (commits, dates, host): [{full_rel}]({full_rel}).\n")
    with open(doc, "w") as f:
        f.write(wrap_md("\n".join(x.rstrip("\n") + "\n" for x in out)
                        .replace("\n\n\n", "\n\n")))


def extra_sections():
    """The sections of other benchmarks (bench/solvers/sections/*.md, in name order): their
    tables are written from their own results, which this report does not read."""
    d = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sections")
    if not os.path.isdir(d):
        return ""
    return "".join(open(os.path.join(d, f)).read().rstrip("\n") + "\n\n" for f in sorted(os.listdir(d))
                   if f.endswith(".md"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--results", required=True)
    ap.add_argument("--plots", required=True, help="directory for the PNG files")
    ap.add_argument("--doc", required=True, help="the summary page (markdown) to write")
    ap.add_argument("--full", help="the full tables (markdown) to write; default: "
                    "full_report.md next to the results file")
    ap.add_argument("--profile", default="full")
    ap.add_argument("--cases", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                     "cases.json"))
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args()
    recs = load(args.results)
    if not recs:
        print(f"report.py: no results in {args.results}", file=sys.stderr)
        return 1
    full = args.full or os.path.join(os.path.dirname(os.path.abspath(args.results)),
                                     "full_report.md")
    os.makedirs(args.plots, exist_ok=True)
    plots = {} if args.no_plots else make_plots(recs, args.plots, cases_of(recs), args.profile)
    if not plots:    # no matplotlib, or --no-plots: link the plots already in the directory
        plots = {fn[:-4]: os.path.join(args.plots, fn) for fn in sorted(os.listdir(args.plots))
                 if re.fullmatch(r"(pareto_.*|time_vs_n|error_vs_order)\.png", fn)}
    write_doc(recs, full, plots, args.profile, args.cases, args.results, page=args.doc)
    write_page(recs, args.doc, plots, args.profile, args.results, full)
    return 0


if __name__ == "__main__":
    sys.exit(main())
