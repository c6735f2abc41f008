#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Compares the rows of an engine benchmark table (bench_engine output, markdown) with the
reference points (exafmm-t / PVFMM, 2 threads, evaluation only, no other job running).
For each reference point the cheapest row (by 1-thread CPU time, the load-independent cost) of
the same configuration and N whose measured force error is at or below the reference error is
taken. Prints a markdown table:
  eval / ref          2-thread wall time of ours over the reference time (our wall time
                      includes any slowdown by other jobs on the same cores)
  CPU/2 / ref         our 1-thread CPU time halved (ideal 2-thread scaling) over the reference
  speed-up, ref s-u   speed-up over the direct sum: ours measured in the same run, the
                      reference's = direct time at 2.2e9 pairs/s over the reference time
  ref s-u / s-u       = our time over the reference time with both normalised by their own
                      direct sum (< 1: faster than the reference)
Usage: anchor_ratios.py doc/engine_benchmark.md"""
import sys

REFS = [  # config, N, force error, reference eval s
    ("uniform", 1e5, 5e-6, 0.21),
    ("uniform", 1e5, 1.5e-7, 0.26),
    ("uniform", 1e5, 1.5e-10, 0.43),
    ("plummer", 1e5, 6e-6, 0.39),
    ("uniform", 1e6, 3e-6, 2.9),
    ("uniform", 1e6, 1e-7, 3.7),
]
REF_DIRECT_RATE = 2.2e9  # pairs/s of the reference 2-thread direct sum (1e5: 4.6 s)


def main(path):
    rows, header = [], None
    for line in open(path):
        if not line.startswith("|"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] == "config":
            header = cells
            continue
        if header is None or cells[0].startswith("---") or len(cells) != len(header):
            continue
        rows.append(dict(zip(header, cells)))
    if not rows:
        sys.exit("no benchmark table in " + path)
    cpu = "1-thread CPU s"
    print("| reference point | ref. eval s | our row (p, leaf) | error | eval s | eval / ref | CPU/2 / ref "
          "| speed-up | ref. speed-up | ref. s-u / our s-u |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for cfg, n, err, tref in REFS:
        cand = [r for r in rows if r["config"] == cfg and abs(float(r["N"]) - n) < 0.5
                and float(r["rel. force err"]) <= err]
        name = f"{cfg} {n:.0e} @ {err:g}"
        if not cand:
            print(f"| {name} | {tref} | (no row at this error) | | | | | | | |")
            continue
        r = min(cand, key=lambda r: float(r[cpu]))
        ev, c1, su = float(r["eval s"]), float(r[cpu]), float(r["speed-up"])
        ref_su = n * n / REF_DIRECT_RATE / tref
        print(f"| {name} | {tref} | p={r['p']}, {r['leaf']} | {float(r['rel. force err']):.2e} | {ev:.3f} "
              f"| {ev / tref:.2f} | {c1 / 2 / tref:.2f} | {su:.1f} | {ref_su:.1f} | {ref_su / su:.2f} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "doc/engine_benchmark.md")
