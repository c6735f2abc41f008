#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# The tree of the distributed evaluation (kspace_style kifmm on several ranks: the leaf size or
# periodic grid chosen on the stand-in of all ranks' points, kifmm::gather_layout and
# choose_tree_from_layout; beyond its size the uniform model's) and the tree tuned by timing from it (as kspace_style kifmm with tune yes) against a sweep of leaf sizes
# (and, periodic, single-level grids), on P ranks of bench_scaling.
#   python3 bench/scaling/tree_sweep_ranks.py [--build build] [--np 2] [--rounds 3] [--span 8]
#       [--cases uniform:1e5:3,6,10 periodic:1e5:3,6,10 plummer:1e5:3,6,10]
# Point sets (bench_scaling): uniform, plummer, clusters (open); periodic (uniform),
# periodic_plummer, periodic_clusters. --span F: the swept leaf sizes (and grids, by their points
# per cell) within a factor F of the automatic tree's (0: all).
# Every candidate is one bench_scaling process: 2 timed evaluations after the same number of
# untimed ones (the tuned tree: its tuning evaluations and one warm-up; every other candidate:
# as many warm-ups, the tuning evaluations counted by a first run of the tuned one, not timed);
# all candidates of a case run in rotating order for --rounds rounds. Time: wall seconds per evaluation (the
# slowest rank). Prints a provenance line and one markdown row per case: automatic, tuned and
# fastest swept tree, their median times, auto / best and tuned / best (medians over the rounds
# of the per-round ratios; below 1: faster than every swept tree) and the tuning evaluations.
import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time


def run(build, np, n, dist, order, how, warmups=1):
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    cmd = ["mpirun", "--bind-to", "none", "-np", str(np), "-x", "OMP_NUM_THREADS",
           os.path.join(build, "bench", "scaling", "bench_scaling"), str(n), dist, str(order), "2", "0", how, "charges",
           str(warmups)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    return json.loads([l for l in out.splitlines() if l.startswith("{")][-1])


def label(r):
    return "grid %d^3" % r["grid"] if r["grid"] > 0 else str(r["leaf"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build")
    ap.add_argument("--np", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--span", type=float, default=8.0)
    ap.add_argument("--cases", nargs="*", default=["uniform:1e5:3,6,10", "periodic:1e5:3,6,10", "plummer:1e5:3,6,10"])
    a = ap.parse_args()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    load = open("/proc/loadavg").read().split()[:3]
    print("commit %s, %s, %d cores, %s, load %s" % (commit, time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                                                    os.cpu_count(), platform.processor() or platform.machine(),
                                                    " ".join(load)))
    print("command: python3 bench/scaling/tree_sweep_ranks.py %s" % " ".join(sys.argv[1:]))
    print("\nwall s per evaluation on %d ranks x 1 thread (slowest rank), medians of %d rounds; every candidate "
          "timed after as many untimed evaluations as the tuned tree (its tuning evaluations + 1)\n" % (a.np, a.rounds))
    print("| points | N | p | ranks | tree auto / tuned / best | depth auto / tuned / best | s auto / tuned / best "
          "| auto/best | tuned/best | candidates | tuning evaluations | points per rank min / max |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for case in a.cases:
        dist, n, orders = case.split(":")
        n = int(float(n))
        for order in [int(o) for o in orders.split(",")]:
            auto = run(a.build, a.np, n, dist, order, "choice")
            # the automatic tree's points per leaf (a grid: per cell)
            per = n / auto["grid"] ** 3 if auto["grid"] > 0 else auto["leaf"]

            def near(m):
                return a.span <= 0 or per / a.span <= m <= per * a.span

            hows = ["choice", "tuned"] + ["leaf=%d" % l for l in (16, 32, 64, 128, 256, 512, 1024, 2048, 4096)
                                          if l <= n and near(l)]
            if dist.startswith("periodic"):
                hows += ["grid=%d" % k for k in (3, 4, 6, 8, 11, 16, 22) if 2 * k ** 3 <= n and near(n / k ** 3)]
            times = {h: [] for h in hows}
            rows = {}
            # the tuning evaluations, for the other candidates' warm-ups
            warm = run(a.build, a.np, n, dist, order, "tuned")["tuning_evaluations"] + 1
            for r in range(a.rounds):
                for k in range(len(hows)):
                    h = hows[(k + r) % len(hows)]
                    try:
                        row = run(a.build, a.np, n, dist, order, h, 1 if h == "tuned" else warm)
                    except subprocess.CalledProcessError:
                        times.pop(h, None)    # a grid beyond the memory bound, or no tree
                        continue
                    if h in times:
                        times[h].append(row["wall"])
                        rows[h] = row
                hows = [h for h in hows if h in times]
            swept = [h for h in hows if h not in ("choice", "tuned")]
            best = min(swept, key=lambda h: statistics.median(times[h]))

            def over_best(h):
                return statistics.median([x / y for x, y in zip(times[h], times[best])])

            ra, rt, rb = rows["choice"], rows["tuned"], rows[best]
            print("| %s | %d | %d | %d | %s / %s / %s | %d / %d / %d | %.4g / %.4g / %.4g | %.2f | %.2f | %d | %d "
                  "| %d / %d |" % (
                dist, n, order, a.np, label(ra), label(rt), label(rb), ra["depth"], rt["depth"], rb["depth"],
                statistics.median(times["choice"]), statistics.median(times["tuned"]), statistics.median(times[best]),
                over_best("choice"), over_best("tuned"), len(swept), rt["tuning_evaluations"], ra["own_min"],
                ra["own_max"]))
            sys.stdout.flush()
    print("\nload after %s" % " ".join(open("/proc/loadavg").read().split()[:3]))


if __name__ == "__main__":
    main()
