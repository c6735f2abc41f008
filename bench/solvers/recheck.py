#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Re-measure stored runs of the campaign: the same bench_solvers command on the same data and
reference files as run_bench.py (the work directory of the campaign), appended as kind
"recheck" to a side file (results/recheck-COMMIT.jsonl) that report.py compares with the
stored runs (how well CPU times measured at different times agree).

  python3 bench/solvers/recheck.py --bin BUILD/bench_solvers --work BUILD/bench_solvers_work \
      --commit C --out bench/solvers/results/recheck-C.jsonl uniform:100000:direct ...
"""

import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from run_bench import append_result, load_results, run_child, run_command  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--results", default=os.path.join(HERE, "results", "results.jsonl"))
    ap.add_argument("--cases", default=os.path.join(HERE, "cases.json"))
    ap.add_argument("--out", required=True, help="side file (JSON lines, appended)")
    ap.add_argument("--commit", default="")
    ap.add_argument("--threads", default=os.environ.get("OMP_NUM_THREADS", "1"))
    ap.add_argument("runs", nargs="+", help="CASE:N:SPEC of stored runs")
    args = ap.parse_args()
    with open(args.cases) as f:
        cfg = json.load(f)
    lim = cfg["limits"]
    scenes = {c["name"]: c["scene"] for p in cfg["profiles"].values() for c in p["cases"]
              if c.get("config") == "scene"}
    done = load_results(args.results)
    env = dict(os.environ)
    env["OMP_NUM_THREADS"] = str(args.threads)
    env["KIFMM_CACHE_DIR"] = os.path.join(args.work, "operator-cache")
    rc = 0
    for item in args.runs:
        case, n, spec = item.split(":", 2)
        n = int(n) if n.isdigit() else n    # scene cases: start / end
        old = done.get(("run", case, n, spec))
        if old is None:
            print(f"{item}: not in {args.results}", file=sys.stderr)
            rc = 1
            continue
        tag = f"{case}_{n}"
        data = os.path.join(args.work, "data", tag + ".data")
        if case in scenes:
            data = os.path.join(args.work, "scenes", f"{scenes[case]}_{n}.data")
        ref = os.path.join(args.work, "ref", tag + ".ref")
        if not (os.path.exists(data) and os.path.exists(ref)):
            print(f"{item}: no data/reference file in {args.work}", file=sys.stderr)
            rc = 1
            continue
        screen = os.path.join(args.work, "logs", f"recheck_{tag}_{spec.replace(':', '_')}.log")
        cmd = run_command(args.bin, data, ref, spec, old.get("clump", 1), "charge", lim, screen,
                          old.get("periodic"))
        t0 = time.time()
        st, res, msg = run_child(cmd, env, lim["timeout_s"], lim["memory_limit_mb"], screen)
        rec = {"kind": "recheck", "case": case, "n": n, "spec": spec,
               "solver": spec.split(":")[0], "status": st, "message": msg,
               "periodic": bool(old.get("periodic")), "clump": old.get("clump", 1),
               "wall": time.time() - t0, "commit": args.commit,
               "omp_threads_env": str(args.threads), "host_cpus": os.cpu_count()}
        rec.update(res or {})
        rec["date"] = time.strftime("%Y-%m-%d %H:%M:%S")
        append_result(args.out, rec)
        ratio = rec.get("c_eval", float("nan")) / old.get("c_eval", float("nan"))
        print(f"{item}: {st} CPU eval {rec.get('c_eval', float('nan')):.4g} s "
              f"(stored {old.get('c_eval', float('nan')):.4g} s, ratio {ratio:.2f}), "
              f"error {rec.get('error', float('nan')):.7g} (stored {old.get('error'):.7g})")
    return rc


if __name__ == "__main__":
    sys.exit(main())
