#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Run the quick variant of the platelets scene from several random starts and tabulate the
outcome the ctest asserts (unittest/examples/check_platelets.py) for each.

For each seed the example directory is copied to a temporary directory, the start is placed
by place_platelets.py with that seed (the quick variant's arguments, as in README.md), the
quick variant runs there, and the first and last frames of out/pebbles.dump are analysed
(nematic order parameter S, polar order, mean nearest-platelet distance) with the checker's
functions. Prints one line per seed and the number that pass (S > 0.9, mean nearest distance
< 1.5 x 0.026 and < 0.6 x its initial value) and appends the lines to --table if given.

usage: sweep_seeds.py --lmp LMP [--seeds 1 2 3 ...] [--jobs 1] [--example DIR] [--keep]
                      [--table FILE] [-- LAMMPS -var args]
Run it with OMP_NUM_THREADS=1 (and nice when other jobs share the cores), e.g.
    OMP_NUM_THREADS=1 nice -n 19 python3 sweep_seeds.py --lmp ../../build/lmp_kifmm \
        --seeds 1 2 3 4 5 6 7 8 9 10 --jobs 2
"""
import argparse
import concurrent.futures
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "unittest", "examples"))
import check_platelets  # noqa: E402

# the quick variant's placement (README.md): 17 platelets of n = 6 in the periodic box L
PLACE = ["--count", "17", "--box", "0.4306", "--radius", "0.0605", "--thickness", "0.026",
         "--periodic"]


def log_cpu(path):
    """CPU seconds of the runs in a LAMMPS log: sum of loop time x % CPU use."""
    total, loop = 0.0, None
    with open(path) as f:
        for line in f:
            if line.startswith("Loop time of"):
                loop = float(line.split()[3])
            elif "% CPU use" in line and loop is not None:
                total += loop * float(line.split("%")[0]) / 100
                loop = None
    return total


def run_seed(example, lmp, seed, extra, keep):
    work = tempfile.mkdtemp(prefix=f"platelets-seed{seed}-")
    copy = os.path.join(work, "platelets")
    shutil.copytree(example, copy, ignore=shutil.ignore_patterns("out", "quick-run", "__pycache__",
                                                             "*.png"))
    os.makedirs(os.path.join(copy, "out"))
    subprocess.run([sys.executable, "place_platelets.py"] + PLACE +
                   ["--seed", str(seed), "-o", "positions-quick.lmp"], cwd=copy, check=True)
    cmd = [lmp, "-in", "in.platelets", "-var", "quick", "1"] + extra + [
        "-log", "out/log.lammps", "-nocite", "-screen", "none"]
    run = subprocess.run(cmd, cwd=copy)
    if run.returncode != 0:
        return seed, None, copy
    cpu = log_cpu(os.path.join(copy, "out", "log.lammps"))
    frames = check_platelets.read_frames(os.path.join(copy, "out", "pebbles.dump"))
    first, last = check_platelets.analyse(frames[0]), check_platelets.analyse(frames[-1])
    # time at which S > 0.9 and the spacing criterion hold from then to the end
    series = [check_platelets.analyse(f) for f in frames]
    settled = None
    for k in range(len(series) - 1, -1, -1):
        if series[k][1] > 0.9 and series[k][3] < 1.5 * 0.026:
            settled = k
        else:
            break
    if not keep:
        shutil.rmtree(work)
    return seed, (first, last, settled, len(series) - 1, cpu), (copy if keep else None)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(1, 11)))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--example", default=HERE,
                    help="directory with in.platelets and its files (default: this one)")
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--table", default=None)
    ap.add_argument("extra", nargs="*", help="extra LAMMPS arguments (after --)")
    a = ap.parse_args()
    lmp = os.path.abspath(a.lmp)
    lines = []
    npass = 0
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        futures = [pool.submit(run_seed, os.path.abspath(a.example), lmp, s, a.extra, a.keep) for s in a.seeds]
        for fut in futures:
            seed, res, kept = fut.result()
            if res is None:
                line = f"seed {seed}: LAMMPS failed (kept in {kept})"
            else:
                first, last, settled, nframes, cpu = res
                ok = (last[1] > 0.9 and last[3] < 1.5 * 0.026 and last[3] < 0.6 * first[3])
                npass += ok
                since = "-" if settled is None else f"{settled / nframes:.2f}"
                line = (f"seed {seed:5d}: S {last[1]:.4f}  polar {last[2]:.4f}  "
                        f"nearest {first[3]:.4f} -> {last[3]:.4f}  "
                        f"passing from t/T_max {since}  "
                        f"{'PASS' if ok else 'FAIL'}  {cpu:.1f} s CPU")
                if kept:
                    line += f"  ({kept})"
            print(line, flush=True)
            lines.append(line)
    summary = f"{npass} of {len(a.seeds)} seeds pass"
    print(summary)
    if a.table:
        with open(a.table, "a") as f:
            f.write("\n".join(lines + [summary]) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
