#!/usr/bin/env python3
"""Fit the cost model of doc/scaling.md to bench/scaling/results/scaling.jsonl and print it.

    python3 bench/scaling/model.py [results.jsonl]

Measured here (2-core machine, ranks oversubscribed beyond 2): CPU seconds per point of one
rank, the extra CPU of the distributed runs per ghost point, ghost points per rank against
the geometric halo model, bytes sent per rank. Assumed (no cluster here): network bandwidth
BETA bytes/s per rank and latency ALPHA s per message; they are parameters of the table.
"""
import json
import math
import sys

ALPHA = 5e-6     # s per message (assumed)
BETA = 5e9       # bytes/s per rank (assumed; a 50-100 Gb/s link shared by the cores of a node)
NSURF = {6: 152, 7: 218, 8: 296}


def choose_top_level(n, p, nsurf, max_depth=20):
    """same rule as kifmm::choose_top_level (engine/distributed.cpp)"""
    best, best_bytes = 2, float("inf")
    side = p ** (1.0 / 3.0)
    for l in range(2, min(5, max_depth) + 1):
        r = side / 2 ** l
        halo = (1 + 2 * r) ** 3 - 1
        b = (32.0 * n / p * halo if p > 1 else 0.0) + 8.0 * nsurf * 8 ** l
        if b < best_bytes:
            best, best_bytes = l, b
    return best


def halo_model(p, level):
    r = p ** (1.0 / 3.0) / 2 ** level
    return (1 + 2 * r) ** 3 - 1


def load(path):
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line.startswith("{"):
                rows.append(json.loads(line))
    return rows


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "bench/scaling/results/scaling.jsonl"
    rows = [r for r in load(path) if r["dist"] == "uniform" and r["order"] == 6]
    one = {r["N"]: r for r in rows if r["ranks"] == 1 and r["threads"] == 1}
    if not one:
        sys.exit("no 1-rank 1-thread run in " + path)
    nbig = max(one)
    c1 = one[nbig]["cpu_sum"] / nbig          # CPU s per point (1 rank, 1 thread)
    # extra CPU per ghost point relative to an own point, from the 2-rank runs (2 ranks on 2
    # cores: no oversubscription, so little MPI busy-waiting in the CPU times)
    fits = []
    for r in rows:
        if r["ranks"] == 2 and r["threads"] == 1 and r["N"] in one and r["ghosts_avg"] > 0:
            extra = r["cpu_sum"] / one[r["N"]]["cpu_sum"] - 1.0
            ghosts = r["ghosts_avg"] * r["ranks"] / r["N"]
            fits.append((ghosts, extra))
    kappa = max(0.0, sum(g * e for g, e in fits) / sum(g * g for g, e in fits)) if fits else 0.0
    # measured halo against the model (P^(1/3) bricks in a cube; LAMMPS grids for small P are
    # slabs/columns, whose halo is smaller than the cubic-domain model at the same P)
    print("# measured (uniform, order 6)")
    print("| N | P | threads | top level | own/rank | ghosts/rank avg (max) | ghosts/own | model (1+2r)^3-1 |"
          " bytes/rank avg (max) | CPU s/eval (sum) | wall s/eval | load avg |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in sorted(rows, key=lambda r: (r["N"], r["ranks"], r["threads"])):
        own = r["own_max"]
        print(f"| {r['N']:.0e} | {r['ranks']} | {r['threads']} | {r['top_level']} | {own:.0f} | "
              f"{r['ghosts_avg']:.0f} ({r['ghosts_max']:.0f}) | {r['ghosts_avg'] / max(own, 1):.2f} | "
              f"{halo_model(r['ranks'], r['top_level']) if r['ranks'] > 1 else 0:.2f} | "
              f"{r['bytes_avg']:.3g} ({r['bytes_max']:.3g}) | {r['cpu_sum']:.3g} | {r['wall']:.3g} | "
              f"{r.get('loadavg', -1):.1f} |")
    print()
    print(f"c1 = {c1:.3e} CPU s per point and evaluation (N = {nbig:.0e}, 1 rank, 1 thread)")
    print(f"kappa = {kappa:.3f} (extra CPU of a ghost point relative to an own point; {len(fits)} runs)")
    print(f"assumed network: latency {ALPHA:.0e} s, bandwidth {BETA:.1e} B/s per rank")
    print()
    print("# model: time per evaluation (s), order 6, uniform, cubic domains")
    print("| N | P | N/P | L | ghosts/own | compute | bytes/rank | comm | comm/compute |")
    print("|---|---|---|---|---|---|---|---|---|")
    nsurf = NSURF[6]
    for n in (1e7, 1e8, 1e9):
        for p in (64, 256, 1024, 4096):
            npr = n / p
            level = choose_top_level(n, p, nsurf)
            h = halo_model(p, level)
            t_comp = c1 * npr * (1 + kappa * h)
            frontier = min(8 ** level, n / 64)
            b_ghost = 32 * npr * h
            b_red = 2 * 8 * nsurf * frontier     # ring allreduce sends about twice the buffer
            b_small = 2 * 16 * 8 ** level + 8 * 26   # counts allreduce, requests
            nbytes = b_ghost + b_red + b_small
            msgs = 4 * 2 * math.log2(p) + 2 * 26 + p   # allreduces, neighbour exchanges, alltoall of counts
            t_comm = ALPHA * msgs + nbytes / BETA
            print(f"| {n:.0e} | {p} | {npr:.3g} | {level} | {h:.2f} | {t_comp:.3g} | {nbytes:.3g} | "
                  f"{t_comm:.3g} | {t_comm / t_comp:.3f} |")
    # where communication dominates: N/P at which comm = compute
    print()
    print("# N/P below which communication exceeds computation (model)")
    print("| P | L | N/P at comm = compute |")
    print("|---|---|---|")
    for p in (64, 256, 1024, 4096):
        lo, hi = 1.0, 1e9
        for _ in range(200):
            mid = math.sqrt(lo * hi)
            n = mid * p
            level = choose_top_level(n, p, nsurf)
            h = halo_model(p, level)
            t_comp = c1 * mid * (1 + kappa * h)
            frontier = min(8 ** level, n / 64)
            nbytes = 32 * mid * h + 2 * 8 * nsurf * frontier + 2 * 16 * 8 ** level
            t_comm = ALPHA * (8 * math.log2(p) + 52 + p) + nbytes / BETA
            if t_comm > t_comp:
                lo = mid
            else:
                hi = mid
        print(f"| {p} | {choose_top_level(hi * p, p, nsurf)} | {hi:.3g} |")


if __name__ == "__main__":
    main()
