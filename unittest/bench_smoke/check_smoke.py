#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Checks of the bench_smoke test on the output of `run.sh --tiny` (open and periodic cases):
the report has the runs table of every case with finite errors, kifmm's error falls as the
requested accuracy is tightened, the exact solvers agree with the reference, and the ratio
tables are there."""

import json
import math
import os
import sys


def fail(msg):
    print(f"bench_smoke: FAIL: {msg}")
    sys.exit(1)


def main(out):
    doc = os.path.join(out, "full_report.md")
    if not os.path.exists(doc):
        fail(f"no report {doc}")
    with open(doc) as f:
        text = f.read()
    for heading in ("## Speed ratio at matched error", "## All runs", "## Pending"):
        if heading not in text:
            fail(f"report lacks '{heading}'")
    # the one-page summary beside it: a table of speed ratios
    summary = os.path.join(out, "summary.md")
    if not os.path.exists(summary):
        fail(f"no summary page {summary}")
    with open(summary) as f:
        if not any(l.startswith("|") for l in f):
            fail("the summary page has no table")

    # runs tables: "### case" then rows "| spec | N | error | ..."
    tables, case = {}, None
    for line in text.splitlines():
        if line.startswith("### "):
            case = line[4:].strip()
        elif case and line.startswith("| ") and not line.startswith("| solver") \
                and not line.startswith("|---"):
            cols = [c.strip() for c in line.strip("|").split("|")]
            tables.setdefault(case, []).append(cols)
    for name in ("uniform", "dipole3", "uniform_periodic"):
        rows = tables.get(name)
        if not rows:
            fail(f"no runs table for case {name}")
        kifmm = []
        for cols in rows:
            spec, status = cols[0], cols[-1]
            if not status.startswith("ok"):
                fail(f"{name}: {spec} did not run: {status}")
            err = float(cols[2])
            if not math.isfinite(err) or err < 0:
                fail(f"{name}: {spec} has error {cols[2]}")
            if spec.startswith("kifmm:acc="):
                acc = float(spec.split("acc=")[1].split(":")[0].split()[0])
                kifmm.append((acc, err, spec))
            if spec.startswith(("direct", "coulcut")) and err > 1e-12:
                fail(f"{name}: exact solver {spec} differs from the reference by {err:.2e}")
            if spec.startswith(("msm", "ewald", "pppm")) and not (0 < err < 1):
                fail(f"{name}: {spec} error {err:.2e} out of range")
        if len(kifmm) < 3:
            fail(f"{name}: {len(kifmm)} kifmm accuracies in the table, expected 3")
        kifmm.sort(reverse=True)    # loosest accuracy first
        for (a1, e1, s1), (a2, e2, s2) in zip(kifmm, kifmm[1:]):
            if not e2 < e1:
                fail(f"{name}: kifmm error does not fall with accuracy: {s1} {e1:.2e}, "
                     f"{s2} {e2:.2e}")
        for acc, err, spec in kifmm:
            if not 0 < err < 10 * acc:
                fail(f"{name}: {spec} error {err:.2e} not below 10x the requested accuracy")
        print(f"bench_smoke: {name}: kifmm errors " +
              ", ".join(f"{a:g} -> {e:.2e}" for a, e, _ in kifmm))

    # the ratio table has a row per case
    ratio_rows = [ln for ln in text.split("## Speed ratio at matched error")[1].split("\n## ")[0]
                  .splitlines() if ln.startswith(("| uniform", "| dipole3"))]
    if len(ratio_rows) < 3:
        fail("speed-ratio tables lack the uniform, dipole3 and uniform_periodic rows")
    # dipole clumps: clump net-force errors were measured
    with open(os.path.join(out, "results.jsonl")) as f:
        recs = [json.loads(ln) for ln in f if ln.strip()]
    # the report uses CPU times only: every run measured them (else it would be left out)
    for r in recs:
        if r.get("kind") == "run" and r.get("status") == "ok":
            for k in ("c_eval",) + (("c_setup",) if r.get("solver") != "direct" else ()):
                if not (r.get(k, -1) > 0 and math.isfinite(r[k])):
                    fail(f"{r['case']} {r['spec']}: no CPU time {k} ({r.get(k)})")
    if "binary): left out of this report" in text:
        fail("the report left runs out for lack of CPU times")
    dip = [r for r in recs if r.get("case") == "dipole3" and r.get("solver") == "kifmm"]
    if not dip or any(r.get("clump_error") is None or not math.isfinite(r["clump_error"])
                      for r in dip):
        fail("dipole3: clump net-force errors missing")
    try:
        import matplotlib    # noqa: F401
        for png in ("pareto_uniform.png", "pareto_dipole3.png"):
            if not os.path.exists(os.path.join(out, png)):
                fail(f"plot {png} missing")
    except ImportError:
        print("bench_smoke: matplotlib not available, plots not checked")
    print("bench_smoke: OK")


if __name__ == "__main__":
    main(sys.argv[1])
