#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Reads the result rows of the anchor benchmark's drivers (lines "round=K ROW key=value ...",
as run.sh collects them) and
  select RAW SET N TARGETS...   prints "code target setting" for each code and target: the setting
                                of least CPU time in round 0 (the sweep) whose error is at or
                                below the target (codes with none are left out)
  orders RAW SET N TARGETS...   prints "code order" for the orders selected for these targets
  table RAW TARGETS...          prints the markdown tables (per code and case; our time over the
                                faster anchor's)
  efficiency RAW1 RAW2 TARGETS...  prints each code's parallel efficiency: its least wall time at
                                one thread (RAW1) over twice its least at two (RAW2), per case
The time compared (selection and ratios) is the CPU time of the process, or the wall time with
ANCHORS_TIME=wall (run.sh sets it for more than one thread).
Codes: ours (order and tree chosen by the engine for a requested accuracy), ours_leaf (ours and,
besides, the order chosen for a requested accuracy with a given leaf size: the best of both),
pvfmm, exafmmt."""
import os
import statistics
import sys

METRIC = os.environ.get("ANCHORS_TIME", "cpu")    # "cpu" or "wall"
MI = 1 if METRIC == "wall" else 0

NAMES = {"ours": "ours (automatic)", "ours_leaf": "ours (best leaf of sweep)", "pvfmm": "PVFMM",
         "exafmmt": "exafmm-t"}
ANCHORS = ("pvfmm", "exafmmt")


def read(path):
    rows = []
    for line in open(path):
        parts = line.split()
        if len(parts) < 2 or not parts[0].startswith("round=") or parts[1] != "ROW":
            continue
        r = dict(p.split("=", 1) for p in [parts[0]] + parts[2:])
        for k in ("round", "n", "order", "leaf", "depth"):
            r[k] = int(r[k])
        for k in ("err", "cpu", "wall"):
            r[k] = float(r[k])
        rows.append(r)
        # a row of ours is also a candidate of "ours_leaf" (the automatic tree is one leaf choice)
        if r["code"] == "ours":
            r2 = dict(r)
            r2["code"] = "ours_leaf"
            rows.append(r2)
            if ":leaf" in r["setting"]:
                r["code"] = "ours_given_leaf"
    return rows


def select(rows, s, n, target):
    """{code: setting} for this case from round 0 (the sweep)"""
    out = {}
    for code in ("ours", "ours_leaf") + ANCHORS:
        cand = [r for r in rows if r["round"] == 0 and r["code"] == code and r["set"] == s and r["n"] == n
                and r["err"] <= target]
        if cand:
            out[code] = min(cand, key=lambda r: r[METRIC])["setting"]
    return out


def case_rows(rows, s, n, code, setting):
    """rows of the timed rounds (>= 1) of this setting; the sweep's row when there are none"""
    rs = sorted((r for r in rows if r["code"] == code and r["set"] == s and r["n"] == n
                 and r["setting"] == setting), key=lambda r: r["round"])
    timed = [r for r in rs if r["round"] >= 1]
    return timed if timed else rs


def per_round(rs):
    """{round: cpu, wall} (the last row of a round)"""
    return {r["round"]: (r["cpu"], r["wall"]) for r in rs}


def cases(rows):
    seen = []
    for r in rows:
        if (r["set"], r["n"]) not in seen:
            seen.append((r["set"], r["n"]))
    return seen


def table(rows, targets):
    out = []
    out.append("| point set | N | target error | code | setting (chosen) | order | leaf | depth | error "
               "| CPU s, median | wall s, median | CPU s per round |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    ratios = []
    for s, n in cases(rows):
        for t in targets:
            sel = select(rows, s, n, t)
            med = {}
            for code in ("ours", "ours_leaf") + ANCHORS:
                if not any(r["code"] == code and r["set"] == s and r["n"] == n for r in rows):
                    continue
                if code == "ours_leaf" and sel.get("ours_leaf") == sel.get("ours") and "ours" in sel:
                    continue    # the best of the sweep is the automatic choice
                if code not in sel:
                    best = min((r["err"] for r in rows if r["code"] == code and r["set"] == s and r["n"] == n))
                    out.append(f"| {s} | {n:.0e} | {t:g} | {NAMES[code]} | (none meets it; least error "
                               f"{best:.2e}) | | | | | | | |")
                    continue
                rs = case_rows(rows, s, n, code, sel[code])
                pr = per_round(rs)
                cpu = statistics.median(v[0] for v in pr.values())
                wall = statistics.median(v[1] for v in pr.values())
                med[code] = (cpu, wall, pr)
                r0 = rs[0]
                out.append(f"| {s} | {n:.0e} | {t:g} | {NAMES[code]} | {sel[code]} | {r0['order']} | {r0['leaf']} "
                           f"| {r0['depth']} | {max(r['err'] for r in rs):.2e} | {cpu:.3f} | {wall:.3f} | "
                           + ", ".join(f"{pr[k][0]:.3f}" for k in sorted(pr)) + " |")
            anchors = [a for a in ANCHORS if a in med]
            for code in ("ours", "ours_leaf"):
                if code not in med or not anchors:
                    continue
                fast = min(anchors, key=lambda a: med[a][MI])
                pr = med[code][2]
                per = []
                for k in sorted(pr):
                    at = [med[a][2][k][MI] for a in anchors if k in med[a][2]]
                    if at:
                        per.append(pr[k][MI] / min(at))
                wall_ratio = med[code][1 - MI] / min(med[a][1 - MI] for a in anchors)
                ratios.append((s, n, t, NAMES[code], NAMES[fast], per, statistics.median(per), wall_ratio))
    out.append("")
    other = "CPU" if METRIC == "wall" else "wall"
    out.append(f"| point set | N | target error | ours | faster anchor (median {METRIC}) | ours / faster anchor, "
               f"{METRIC}, per round | median | ratio of median {other} times | <= 0.67 |")
    out.append("|---|---|---|---|---|---|---|---|---|")
    for s, n, t, code, fast, per, m, w in ratios:
        out.append(f"| {s} | {n:.0e} | {t:g} | {code} | {fast} | " + ", ".join(f"{x:.2f}" for x in per)
                   + f" | {m:.3f} | {w:.2f} | {'yes' if m <= 0.67 else 'no'} |")
    return "\n".join(out)


def least_wall(rows, s, n, code, target):
    """median wall time (timed rounds) of the code's setting of least wall time meeting the target"""
    cand = [r for r in rows if r["round"] == 0 and r["code"] == code and r["set"] == s and r["n"] == n
            and r["err"] <= target]
    if not cand:
        return None
    setting = min(cand, key=lambda r: r["wall"])["setting"]
    return setting, statistics.median(v[1] for v in per_round(case_rows(rows, s, n, code, setting)).values())


def efficiency(rows1, rows2, targets):
    out = ["| point set | N | target error | code | one thread: setting, wall s | two threads: setting, wall s "
           "| parallel efficiency |", "|---|---|---|---|---|---|---|"]
    for s, n in cases(rows2):
        for t in targets:
            for code in ("ours",) + ANCHORS:
                a, b = least_wall(rows1, s, n, code, t), least_wall(rows2, s, n, code, t)
                if a and b:
                    out.append(f"| {s} | {n:.0e} | {t:g} | {NAMES[code]} | {a[0]}, {a[1]:.3f} | {b[0]}, {b[1]:.3f} "
                               f"| {a[1] / (2 * b[1]):.2f} |")
    return "\n".join(out)


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    cmd, raw = argv[1], argv[2]
    rows = read(raw)
    if cmd in ("select", "orders"):
        s, n, targets = argv[3], int(float(argv[4])), [float(x) for x in argv[5:]]
        orders = set()
        for t in targets:
            sel = select(rows, s, n, t)
            for code in ("ours", "ours_leaf") + ANCHORS:
                if code in sel:
                    if cmd == "select":
                        print(code, f"{t:g}", sel[code])
                    else:
                        r = case_rows(rows, s, n, code, sel[code])[0]
                        orders.add((code, r["order"]))
        for code, o in sorted(orders):
            print(code, o)
    elif cmd == "table":
        print(table(rows, [float(x) for x in argv[3:]]))
    elif cmd == "efficiency":
        print(efficiency(rows, read(argv[3]), [float(x) for x in argv[4:]]))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv)
