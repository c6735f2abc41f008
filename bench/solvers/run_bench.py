#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Measure: run the cases of one profile of cases.json with bench_solvers, one child process
per solver run (so that each run's peak memory is its own), and append one JSON line per run
to the results file. Runs already in the results file are skipped (the campaign can be
stopped and resumed); --force reruns them.

Per case and N: the configuration is generated once (data file), the exact reference is
computed once (direct sum on all atoms up to limits.full_reference_max_n, else on a random
sample of limits.reference_sample atoms, whole clumps), then every solver is run on the same
data file against the same reference.
"""

import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))


EXACT_SOLVERS = ("direct", "coulcut")
COMPETITORS = ("msm", "ewald", "pppm")


def log(msg):
    print(msg, flush=True)


def load_results(path):
    done = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                line = line.strip()
                if not line:
                    continue
                try:
                    r = json.loads(line)
                except json.JSONDecodeError:
                    continue    # a line cut by an interrupted run
                done[(r.get("kind"), r.get("case"), r.get("n"), r.get("spec"))] = r
    return done


def append_result(path, rec):
    with open(path, "a") as f:
        f.write(json.dumps(rec, sort_keys=True) + "\n")


def rss_mb(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


def cpu_s(pid):
    """CPU time (user + system, all threads) of a running process, from /proc."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return 0.0


WALL_FACTOR = 4.0    # a child is also stopped at this many times the limit in wall time


def run_command(binary, data, ref, spec, clump, atom_style, lim, screen, periodic):
    """The bench_solvers command of one measured run (repeats and minimum time from the
    limits of cases.json)."""
    cmd = [binary, "run", "--data", data, "--ref", ref, "--solver", spec,
           "--clump", str(clump), "--atom-style", atom_style,
           "--repeats", str(lim["repeats"]), "--min-time", str(lim["min_time_s"]),
           "--screen", screen]
    if periodic:
        cmd.append("--periodic")
    return cmd


def run_child(cmd, env, timeout, mem_limit_mb, screen):
    """Runs cmd; returns (status, result dict or None, message). Kills the child (and only it)
    when it exceeds the memory limit or the time limit: `timeout` seconds of CPU time (the
    measure of this campaign: the cores are shared), or WALL_FACTOR times that in wall time."""
    t0 = time.time()
    with open(screen + ".stdout", "w") as out, open(screen + ".stderr", "w") as err:
        p = subprocess.Popen(cmd, stdout=out, stderr=err, env=env)
        status = None
        peak = 0.0
        while p.poll() is None:
            time.sleep(0.2)
            peak = max(peak, rss_mb(p.pid))
            if cpu_s(p.pid) > timeout or time.time() - t0 > WALL_FACTOR * timeout:
                status = "timeout"
            elif peak > mem_limit_mb:
                status = "memory"
            if status:
                p.kill()
                p.wait()
                break
    result = None
    with open(screen + ".stdout") as f:
        for line in f:
            if line.startswith("RESULT "):
                result = json.loads(line[7:])
    if status:
        msg = (f"killed after {time.time() - t0:.0f} s wall (limit {timeout} s CPU, "
               f"{WALL_FACTOR * timeout:.0f} s wall)" if status == "timeout"
               else f"killed at {peak:.0f} MB RSS (limit {mem_limit_mb} MB)")
        return status, result, msg
    if p.returncode != 0 or result is None:
        tail = ""
        for fn in (screen + ".stderr", screen):
            if os.path.exists(fn):
                with open(fn, errors="replace") as f:
                    lines = [ln.strip() for ln in f if ln.strip()]
                errs = [ln for ln in lines if "ERROR" in ln or "bench_solvers:" in ln]
                if errs:
                    tail = errs[-1]
                    break
                if lines and not tail:
                    tail = lines[-1]
        return "failed", result, f"exit code {p.returncode}: {tail}"[:300]
    return "ok", result, ""


def expand(case, sets):
    specs = []
    for s in case["solvers"]:
        for spec in (sets[s] if s in sets else [s]):
            if spec not in specs:
                specs.append(spec)
    return specs


def pareto(points):
    """(time, error) points -> the ones not dominated (faster and more accurate)."""
    pts = sorted(points, key=lambda p: (p[0], p[1]))
    front, best = [], float("inf")
    for p in pts:
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--profile", default="full")
    ap.add_argument("--cases", default=os.path.join(HERE, "cases.json"))
    ap.add_argument("--bin", required=True, help="bench_solvers executable")
    ap.add_argument("--work", required=True, help="directory for data, references and logs")
    ap.add_argument("--results", required=True, help="results file (JSON lines, appended)")
    ap.add_argument("--only", default="", help="comma-separated case names")
    ap.add_argument("--max-n", type=float, default=0, help="skip N above this")
    ap.add_argument("--min-n", type=float, default=0, help="skip N below this")
    ap.add_argument("--force", action="store_true", help="rerun runs already in the results")
    ap.add_argument("--threads", default=os.environ.get("OMP_NUM_THREADS", "1"))
    ap.add_argument("--commit", default="", help="source commit of the binary (recorded)")
    ap.add_argument("--lmp", default="", help="lmp_kifmm, to make the scene snapshots")
    ap.add_argument("--solvers", default="",
                    help="comma-separated solver names (kifmm, msm, ewald, ...) or full specs: "
                         "run only these (the others are neither run nor recorded)")
    ap.add_argument("--timeout", type=float, default=0,
                    help="per-run CPU time limit [s] of this invocation (replaces "
                         "limits.timeout_s and limits.large_n_timeout_s; recorded per run)")
    args = ap.parse_args()

    with open(args.cases) as f:
        cfg = json.load(f)
    prof = cfg["profiles"][args.profile]
    sets, lim = cfg["solver_sets"], dict(cfg["limits"])
    lim.update(prof.get("limits", {}))
    if args.timeout > 0:
        lim["timeout_s"] = lim["large_n_timeout_s"] = args.timeout
    wanted = set(filter(None, args.solvers.split(",")))

    def selected(spec):
        return not wanted or spec in wanted or spec.split(":")[0] in wanted
    for d in ("data", "ref", "logs", "operator-cache"):
        os.makedirs(os.path.join(args.work, d), exist_ok=True)
    env = dict(os.environ)
    env["OMP_NUM_THREADS"] = str(args.threads)
    env["KIFMM_CACHE_DIR"] = os.path.join(args.work, "operator-cache")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    done = {} if args.force else load_results(args.results)
    only = set(filter(None, args.only.split(",")))
    common = {"profile": args.profile, "omp_threads_env": str(args.threads),
              "host_cpus": os.cpu_count(), "commit": args.commit}

    def record(rec):
        rec.update(common)
        rec["date"] = time.strftime("%Y-%m-%d %H:%M:%S")
        append_result(args.results, rec)
        done[(rec.get("kind"), rec.get("case"), rec.get("n"), rec.get("spec"))] = rec

    # operator setup cost per order, on N uniform atoms (enough for a tree of several levels
    # at every order): first a run that fills the operator cache the later runs read
    # (kind setup_fill), then the cold setup without cache and the warm one from the cache
    orders = prof.get("setup_orders", [])
    setup_n = int(prof.get("setup_n", 100000))
    if orders and (not only or "setup" in only) and selected("kifmm"):
        data = os.path.join(args.work, "data", f"setup_uniform_{setup_n}.data")
        ref = os.path.join(args.work, "ref", f"setup_uniform_{setup_n}.ref")
        if not os.path.exists(ref):
            subprocess.run([args.bin, "gen", "--config", "uniform", "--n", str(setup_n),
                            "--seed", "1", "--out", data], check=True, env=env,
                           stdout=subprocess.DEVNULL)
            subprocess.run([args.bin, "ref", "--data", data, "--out", ref, "--sample", "2000"],
                           check=True, env=env, stdout=subprocess.DEVNULL)
        for p in orders:
            for kind, spec in (("setup_fill", f"kifmm:order={p}"),
                               ("setup", f"kifmm:order={p}:cache=none"),
                               ("setup", f"kifmm:order={p}")):
                key = (kind, "setup", setup_n, spec)
                if key in done:
                    continue
                screen = os.path.join(args.work, "logs", f"{kind}_{spec.replace(':', '_')}.log")
                st, res, msg = run_child([args.bin, "run", "--data", data, "--ref", ref,
                                          "--solver", spec, "--min-time", "0.2", "--repeats",
                                          "1", "--screen", screen], env, lim["timeout_s"],
                                         lim["memory_limit_mb"], screen)
                rec = {"kind": kind, "case": "setup", "n": setup_n, "spec": spec, "status": st,
                       "message": msg}
                rec.update(res or {})
                record(rec)
                log(f"{kind} {spec}: {st} setup {rec.get('t_setup', float('nan')):.3g} s")

    for case in prof["cases"]:
        name = case["name"]
        if only and name not in only:
            continue
        if not case.get("enabled", True):
            log(f"case {name}: disabled ({case.get('pending', 'pending')})")
            continue
        specs = expand(case, sets)
        inputs = []
        if case["config"] == "scene":
            # start and end states of an example scene (scene_snapshots.py makes them once)
            scene = case["scene"]
            sdir = os.path.join(args.work, "scenes")
            missing = [s for s in ("start", "end")
                       if not os.path.exists(os.path.join(sdir, f"{scene}_{s}.json"))]
            if missing and args.lmp and os.path.exists(args.lmp):
                log(f"case {name}: running the scene {scene} for its snapshots")
                subprocess.run([sys.executable, os.path.join(HERE, "scene_snapshots.py"),
                                "--lmp", args.lmp, "--work", args.work, "--scenes", scene]
                               + (["--full"] if case.get("full") else []), env=env)
            for state in ("start", "end"):
                path = os.path.join(sdir, f"{scene}_{state}.data")
                if not os.path.exists(path):
                    log(f"case {name}: no {state} snapshot (needs lmp_kifmm: --lmp)")
                    continue
                inputs.append((state, path, state))
        elif case["config"] == "data":
            for fn in case["files"]:
                path = os.path.join(ROOT, fn)
                if not os.path.exists(path):
                    log(f"case {name}: {fn} does not exist yet, skipped")
                    continue
                with open(path) as f:
                    natoms = next(int(ln.split()[0]) for ln in f if ln.strip().endswith("atoms"))
                inputs.append((natoms, path, os.path.basename(fn)))
        else:
            for n in case["n"]:
                inputs.append((n, None, None))
        prev_n = None
        for n, given, label in inputs:
            if args.max_n and isinstance(n, int) and n > args.max_n:
                continue
            if args.min_n and isinstance(n, int) and n < args.min_n:
                prev_n = n    # (the competitors at the next N are pruned from this N's runs)
                continue
            tag = f"{name}_{label or n}"
            data = given or os.path.join(args.work, "data", tag + ".data")
            meta_path = os.path.join(args.work, "data", tag + ".json")
            if case["config"] == "scene":
                meta_path = given[:-len(".data")] + ".json"
            atom_style = case.get("atom_style", "charge")
            if not os.path.exists(meta_path):
                if given:
                    meta = {"natoms": n, "clump": case.get("clump", 1)}
                else:
                    cmd = [args.bin, "gen", "--config", case["config"], "--n", str(n),
                           "--seed", str(case.get("seed", 1)), "--out", data]
                    for k, v in case.get("args", {}).items():
                        cmd += [f"--{k}", os.path.join(ROOT, v) if k == "mol" else v]
                    out = subprocess.run(cmd, check=True, env=env, capture_output=True, text=True)
                    meta = json.loads(next(ln[7:] for ln in out.stdout.splitlines()
                                           if ln.startswith("RESULT ")))
                with open(meta_path, "w") as f:
                    json.dump(meta, f)
            with open(meta_path) as f:
                meta = json.load(f)
            clump = meta.get("clump", 1)
            natoms = meta["natoms"]
            periodic = bool(case.get("periodic", False) or meta.get("periodic", False))
            ref = os.path.join(args.work, "ref", tag + ".ref")
            # open boundaries above direct_max_n: the reference on a sample also times the
            # direct sum (CPU time on the sampled targets, all sources), which is the direct
            # sum's cost at that N scaled by N / sampled; a sampled reference also holds the
            # RMS force over all atoms (f_rms_all, the denominator of the errors); references
            # made before those fields existed are made again (same sample, same forces)
            prev_ref = done.get(("reference", name, n, "reference"))
            stale = prev_ref is not None and (
                (not periodic and natoms > lim["direct_max_n"] and "c_direct_sum" not in prev_ref)
                or (0 < prev_ref.get("sampled", natoms) < natoms and "f_rms_all" not in prev_ref))
            if prev_ref is None or stale or not os.path.exists(ref):
                cmd = [args.bin, "ref", "--data", data, "--out", ref, "--clump", str(clump),
                       "--atom-style", atom_style]
                if periodic:
                    # "engine": kifmm::periodic_direct_sum (Ewald with libm erfc), sampled
                    # above periodic_full_reference_max_n; a number: LAMMPS ewald at it
                    pref = prof.get("periodic_reference", "engine")
                    cmd += ["--periodic", pref]
                    if pref == "engine" and natoms > lim["periodic_full_reference_max_n"]:
                        cmd += ["--sample", str(lim["periodic_reference_sample"])]
                elif natoms > lim["full_reference_max_n"]:
                    cmd += ["--sample", str(lim["reference_sample"])]
                t0 = time.time()
                out = subprocess.run(cmd, env=env, capture_output=True, text=True)
                if out.returncode != 0:
                    log(f"{tag}: reference failed: {out.stderr.strip()[-300:]}")
                    continue
                res = json.loads(next(ln[7:] for ln in out.stdout.splitlines()
                                      if ln.startswith("RESULT ")))
                rec = {"kind": "reference", "case": name, "n": n, "spec": "reference",
                       "status": "ok", "periodic": periodic, "clump": clump,
                       "clump_scale": meta.get("clump_scale", 1.0), "config": case["config"],
                       "wall": time.time() - t0}
                rec.update(res)
                record(rec)
                log(f"{tag}: reference on {res['sampled']} of {res['natoms']} atoms, "
                    f"{rec['wall']:.1f} s")
            # competitors (msm, ewald, pppm) at large N: only the settings that were on that
            # solver's Pareto front (CPU time, error) at the previous N of the case
            keep = {}
            if prev_n is not None and isinstance(n, int) and n >= lim["prune_competitors_from_n"]:
                for comp in COMPETITORS:
                    prev = [r for (k, c, nn, s), r in done.items()
                            if k == "run" and c == name and nn == prev_n
                            and r.get("solver") == comp and r.get("status") == "ok"]
                    if prev:
                        pts = [(r.get("c_eval", r["t_eval"]), r["error"]) for r in prev]
                        front = pareto(pts)
                        keep[comp] = {r["spec"] for r, p in zip(prev, pts) if p in front}
            prev_n = n
            for spec in specs:
                solver = spec.split(":")[0]
                if not selected(spec):
                    continue
                if solver == "direct" and natoms > lim["periodic_direct_max_n" if periodic
                                                       else "direct_max_n"]:
                    continue
                if solver == "coulcut" and (periodic or natoms > lim["coulcut_max_n"]):
                    continue
                if solver in ("ewald", "pppm") and not periodic:
                    continue
                if solver == "msm" and periodic:
                    continue
                if solver in keep and spec not in keep[solver]:
                    continue
                key = ("run", name, n, spec)
                if key in done and done[key].get("status") != "skipped":
                    continue    # (a skipped setting is judged again: the rule may change)
                # at the largest N (limits.large_n) only a few kifmm settings (enough to
                # bracket the matched errors) and a tighter per-run limit: campaign time
                large = natoms >= lim.get("large_n", float("inf"))
                timeout = lim.get("large_n_timeout_s", lim["timeout_s"]) if large \
                    else lim["timeout_s"]
                if large and solver == "kifmm" and spec not in lim.get("large_n_kifmm", [spec]):
                    why = f"not run at N >= {lim['large_n']:g} (campaign time)"
                    record({"kind": "run", "case": name, "n": n, "spec": spec, "solver": solver,
                            "status": "skipped", "message": why, "clump": clump,
                            "periodic": periodic, "config": case["config"],
                            "hard": case.get("hard", ""), "natoms": natoms})
                    log(f"{tag} {spec}: skipped, {why}")
                    continue
                # a setting that failed at a smaller N, or whose CPU time at the previous N
                # where it ran, scaled with N, would exceed the time limit, is not run again
                # (recorded as skipped)
                smaller = [r for (k, c, nn, s), r in done.items()
                           if k == "run" and c == name and s == spec and isinstance(n, int)
                           and isinstance(nn, int) and nn < n and r.get("status") != "skipped"]
                why = ""
                for r in smaller:
                    if r.get("status") not in ("ok", None):
                        why = f"{r['status']} at N = {r['n']}"
                ran = [r for r in smaller if r.get("status") == "ok" and r.get("natoms")]
                if not why and ran:
                    r = max(ran, key=lambda x: x["natoms"])
                    # cost ~ N (kifmm, msm, pppm), N^2 (direct sums), N^2.25 for ewald (its
                    # real-space cutoff is a fixed number of spacings, so the k vectors grow
                    # as N; measured 161x and 173x from 1e4 to 1e5 at acc 1e-3 and 1e-4);
                    # kifmm's operator setup (setup minus its evaluation) does not grow with
                    # N. A run is the setup (which includes one evaluation) and `repeats` more
                    expo = {"ewald": 2.25}.get(solver, 2.0 if solver in EXACT_SOLVERS else 1.0)
                    scale = (natoms / r["natoms"]) ** expo
                    ev = r.get("c_eval", r["t_eval"])
                    over = max(0.0, r.get("c_setup", r["t_setup"]) - ev)
                    cost = ((over if solver == "kifmm" else over * scale)
                            + (1 + lim["repeats"]) * ev * scale)
                    if cost > timeout:
                        why = (f"predicted {cost:.0f} s CPU from N = {r['n']} "
                               f"(limit {timeout} s)")
                if why:
                    record({"kind": "run", "case": name, "n": n, "spec": spec, "solver": solver,
                            "status": "skipped", "message": why, "clump": clump,
                            "periodic": periodic, "config": case["config"],
                            "hard": case.get("hard", ""), "natoms": natoms})
                    log(f"{tag} {spec}: skipped, {why}")
                    continue
                screen = os.path.join(args.work, "logs", f"{tag}_{spec.replace(':', '_')}.log")
                cmd = run_command(args.bin, data, ref, spec, clump, atom_style, lim, screen,
                                  periodic)
                t0 = time.time()
                st, res, msg = run_child(cmd, env, timeout, lim["memory_limit_mb"], screen)
                rec = {"kind": "run", "case": name, "n": n, "spec": spec, "solver": solver,
                       "status": st, "message": msg, "clump": clump, "periodic": periodic,
                       "config": case["config"], "hard": case.get("hard", ""),
                       "wall": time.time() - t0, "cpu_limit_s": timeout}
                rec.update(res or {})
                rec["solver"] = solver
                record(rec)
                if st == "ok":
                    log(f"{tag} {spec}: error {rec['error']:.2e}  eval {rec['t_eval']:.3g} s  "
                        f"setup {rec['t_setup']:.3g} s  mem {rec['mem_mb']:.0f} MB")
                else:
                    log(f"{tag} {spec}: {st} {msg}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
