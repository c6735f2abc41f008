#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Fit the cost model of doc/scaling.md to bench/scaling/results/scaling.jsonl and print it.

    python3 bench/scaling/model.py [results.jsonl]

Measured (on 2 cores, ranks oversubscribed beyond 2): CPU seconds per point of one
rank, the extra CPU of the distributed runs per ghost point, ghost points per rank against
the geometric halo model, bytes sent per rank. Assumed (no cluster here): network bandwidth
BETA bytes/s per rank and latency ALPHA s per message; they are parameters of the table.
The load average of each run is in its JSON line (loadavg); the tables leave it out.
"""
import json
import math
import sys

ALPHA = 5e-6     # s per message (assumed)
BETA = 5e9       # bytes/s per rank (assumed; a 50-100 Gb/s link shared by the cores of a node)
NSURF = {6: 152, 7: 218, 8: 296}


def choose_top_level(n, p, nsurf, max_depth=20, leaf_size=256):
    """same rule as kifmm::choose_top_level (engine/distributed.cpp)"""
    best, best_cost = 2, float("inf")
    side = p ** (1.0 / 3.0)
    leaves = 2.0 * n / leaf_size + 1.0
    for l in range(2, min(5, max_depth) + 1):
        r = side / 2 ** l
        halo = (1 + 2 * r) ** 3 - 1
        ghosts = n / p * halo if p > 1 else 0.0
        cost = ghosts * (32.0 + 4096.0) + 8.0 * nsurf * min(8 ** l, leaves)
        if cost < best_cost:
            best, best_cost = l, cost
    return best


def halo_model(p, level):
    """ghosts/own when whole frontier cells are imported (the layer of frontier cells around a
    cubic domain; also the halo of locally essential trees where frontier cells are leaves)"""
    r = p ** (1.0 / 3.0) / 2 ** level
    return (1 + 2 * r) ** 3 - 1


M_LEAF = 244.0   # mean points per leaf of the cost model's tree for uniform points at order 6


def let_halo(n, p, level, aligned):
    """ghosts/own with locally essential trees: the layer of leaves around a cubic domain (leaf
    side / domain side s = (m / (N/P))^(1/3), at most the frontier cell's r), plus, where the
    domains do not follow the frontier cells, the frontier cells a rank is responsible for but
    shares ((1 + r)^3 - 1: the cells straddling its faces; an upper bound)"""
    r = p ** (1.0 / 3.0) / 2 ** level
    s = min(r, (M_LEAF / (n / p)) ** (1.0 / 3.0))
    h = (1 + 2 * s) ** 3 - 1
    if not aligned and s < r:
        h += (1 + r) ** 3 - 1
    return min(h, halo_model(p, level))    # never more than the whole neighbouring frontier cells


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
        if r.get("tag", "").startswith(("let-", "whole-cells-")):
            continue    # one evaluation each, forced top levels: not for the fit
        if r["ranks"] == 2 and r["threads"] == 1 and r["N"] in one and r["ghosts_avg"] > 0:
            extra = r["cpu_sum"] / one[r["N"]]["cpu_sum"] - 1.0
            ghosts = r["ghosts_avg"] * r["ranks"] / r["N"]
            fits.append((ghosts, extra))
    kappa = max(0.0, sum(g * e for g, e in fits) / sum(g * g for g, e in fits)) if fits else 0.0
    # measured halo against the model (P^(1/3) bricks in a cube; LAMMPS grids for small P are
    # slabs/columns, whose halo is smaller than the cubic-domain model at the same P)
    print("# measured (uniform, order 6)")
    print("| N | P | threads | top level | own/rank | ghosts/rank avg (max) | ghosts/own | model (1+2r)^3-1 |"
          " bytes/rank avg (max) | CPU s/eval (sum) | wall s/eval |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in sorted(rows, key=lambda r: (r["N"], r["ranks"], r["threads"])):
        own = r["own_max"]
        print(f"| {r['N']:.0e} | {r['ranks']} | {r['threads']} | {r['top_level']} | {own:.0f} | "
              f"{r['ghosts_avg']:.0f} ({r['ghosts_max']:.0f}) | {r['ghosts_avg'] / max(own, 1):.2f} | "
              f"{halo_model(r['ranks'], r['top_level']) if r['ranks'] > 1 else 0:.2f} | "
              f"{r['bytes_avg']:.3g} ({r['bytes_max']:.3g}) | {r['cpu_sum']:.3g} | {r['wall']:.3g} |")
    print()
    print(f"c1 = {c1:.3e} CPU s per point and evaluation (N = {nbig:.0e}, 1 rank, 1 thread)")
    print(f"kappa = {kappa:.3f} (extra CPU of a ghost point relative to an own point; {len(fits)} runs)")
    print(f"assumed network: latency {ALPHA:.0e} s, bandwidth {BETA:.1e} B/s per rank")
    print()
    # measured: locally essential trees against whole frontier cells (run_scaling.sh with
    # KIFMM_SCALING_ONLY=let: the same points and top levels, a build of each scheme)
    let_tags = sorted({r["tag"] for r in rows if r.get("tag", "").startswith("let-")})
    if let_tags:
        tag = let_tags[-1]
        # run order of run_scaling.sh: per N and P, top levels 2, 3, automatic; each LET run is
        # followed by the whole-cell run of the other build
        pairs, seen = [], {}
        for i, r in enumerate(rows):
            if r.get("tag") != tag:
                continue
            b = rows[i + 1] if i + 1 < len(rows) else None
            if not b or not b.get("tag", "").startswith("whole-cells-") or (b["N"], b["ranks"]) != (r["N"], r["ranks"]):
                continue
            k = seen.get((r["N"], r["ranks"]), 0)
            seen[(r["N"], r["ranks"])] = k + 1
            pairs.append((("2", "3", "auto")[k] if k < 3 else "?", r, b))
        print("# measured: locally essential trees against whole frontier cells")
        print("| N | P | top level (L) | own/rank | ghosts/rank avg (max): whole / LET | bytes/rank avg (max): whole / LET |"
              " of which LET (max) | LET cells/rank | CPU s/eval (sum): whole / LET |")
        print("|---|---|---|---|---|---|---|---|---|")
        for req, r, b in sorted(pairs, key=lambda x: (x[1]["N"], x[1]["ranks"], x[0])):
            print(f"| {r['N']:.0e} | {r['ranks']} | {req} ({r['top_level']}) | {r['own_max']:.0f} | "
                  f"{b['ghosts_avg']:.0f} ({b['ghosts_max']:.0f}) / {r['ghosts_avg']:.0f} ({r['ghosts_max']:.0f}) | "
                  f"{b['bytes_avg']:.3g} ({b['bytes_max']:.3g}) / {r['bytes_avg']:.3g} ({r['bytes_max']:.3g}) | "
                  f"{r['let_bytes_max']:.3g} | {r['let_cells_avg']:.0f} | {b['cpu_sum']:.3g} / {r['cpu_sum']:.3g} |")
        print()
    # LET: bytes of the cells and densities sent with the LET points, per ghost point byte
    # (fitted to the runs with forced coarse frontier cells, where every ghost comes by LET)
    let_rows = [r for r in rows if r.get("let_bytes_max", 0) > 0 and r["N"] >= 1e6 and r["ranks"] in (2, 4, 8)]
    let_f = (sum(r["let_bytes_max"] / (32.0 * r["ghosts_max"]) - 1.0 for r in let_rows) / len(let_rows)
             if let_rows else 0.5)
    print(f"LET cells and densities: {let_f:.2f} bytes per byte of LET points ({len(let_rows)} runs)")
    print()
    print("# model: time per evaluation (s), order 6, uniform, cubic domains")
    print("Whole cells: the frontier-cell halo when whole frontier cells are imported. "
          "LET: aligned = LAMMPS's domains follow the frontier cells (power-of-two grids of a periodic "
          "box); not aligned = plus the shared frontier cells imported whole (upper bound).")
    print()
    print("| N | P | N/P | L | ghosts/own: whole cells / LET aligned / LET not aligned | ideal c1 N/P |"
          " compute: whole / LET al. / LET not al. | bytes/rank (LET not al.) | comm | comm share |"
          " efficiency: whole / LET al. / LET not al. |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    nsurf = NSURF[6]

    def model(n, p, mode):
        npr = n / p
        level = choose_top_level(n, p, nsurf)
        if mode == "whole":
            h, h_let = halo_model(p, level), 0.0
        else:
            h = let_halo(n, p, level, mode == "aligned")
            h_let = let_halo(n, p, level, True)    # the part that comes as LET (points + cells)
        t_comp = c1 * npr * (1 + kappa * h)
        frontier = min(8 ** level, 2 * n / 256)
        b_ghost = 32 * npr * h + let_f * 32 * npr * h_let
        b_red = 2 * 8 * nsurf * frontier     # ring allreduce sends about twice the buffer
        b_small = 2 * 16 * 8 ** level + 8 * 26   # count reductions, requests
        nbytes = b_ghost + b_red + b_small
        msgs = 4 * 2 * math.log2(p) + 4 * 26 + 2 * level   # allreduces, neighbour messages (sparse exchanges)
        t_comm = ALPHA * msgs + nbytes / BETA
        return level, h, t_comp, nbytes, t_comm

    for n in (1e7, 1e8, 1e9):
        for p in (64, 256, 1024, 4096):
            res = {m: model(n, p, m) for m in ("whole", "aligned", "not")}
            level = res["not"][0]
            ideal = c1 * n / p
            eff = {m: ideal / (res[m][2] + res[m][4]) for m in res}
            _, h, t_comp, nbytes, t_comm = res["not"]
            print(f"| {n:.0e} | {p} | {n / p:.3g} | {level} | {res['whole'][1]:.2f} / {res['aligned'][1]:.2f} / "
                  f"{h:.2f} | {ideal:.3g} | {res['whole'][2]:.3g} / {res['aligned'][2]:.3g} / {t_comp:.3g} | "
                  f"{nbytes:.3g} | {t_comm:.3g} | {t_comm / (t_comp + t_comm):.3f} | "
                  f"{eff['whole']:.2f} / {eff['aligned']:.2f} / {eff['not']:.2f} |")
    print()
    print("# N/P below which communication is more than 10% of the time (LET, not aligned), and the efficiency there")
    print("| P | N/P | L | ghosts/own | efficiency |")
    print("|---|---|---|---|---|")
    for p in (64, 256, 1024, 4096):
        lo, hi = 1.0, 1e9
        for _ in range(200):
            mid = math.sqrt(lo * hi)
            level, h, t_comp, nbytes, t_comm = model(mid * p, p, "not")
            if t_comm > 0.1 * (t_comp + t_comm):
                lo = mid
            else:
                hi = mid
        level, h, t_comp, nbytes, t_comm = model(hi * p, p, "not")
        print(f"| {p} | {hi:.3g} | {level} | {h:.2f} | {c1 * hi / (t_comp + t_comm):.2f} |")


if __name__ == "__main__":
    main()
