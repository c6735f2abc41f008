#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Speed-versus-error report of the long-range solvers (kspace kifmm, LAMMPS msm, ewald, pppm,
# direct sum): builds bench_solvers, measures (run_bench.py, resumable), writes the summary
# page, the full tables and the plots (report.py).
#
#   bash bench/solvers/run.sh            full campaign (hours on 1 core): results, plots and
#                                        the full tables (full_report.md) in
#                                        bench/solvers/results/, summary in doc/benchmarks.md
#   bash bench/solvers/run.sh --quick    N <= 1e4, few solvers (minutes): into the build dir
#   bash bench/solvers/run.sh --tiny     the smoke test's inputs (seconds)
# With --quick and --tiny the output directory holds the full tables (full_report.md) and the
# summary (summary.md).
# Options: --out DIR (results + plots), --doc FILE (summary page), --full FILE (full tables),
#   --build DIR (default: build/ of this checkout, or $KIFMM_BUILD_DIR), --bin PATH (no build),
#   --only CASE[,CASE], --max-n N, --min-n N, --force (rerun what the results file has),
#   --report-only, --threads T (OMP_NUM_THREADS of the runs, default 1), --commit C (source
#   commit of --bin, recorded in the results; default: this checkout's HEAD, "+dirty" if src/
#   has changes),
#   --solvers S[,S] (run only these solver names or specs, e.g. kifmm), --timeout SEC (per-run
#   CPU limit of this invocation). Remeasuring kifmm on a new engine: move its runs out of
#   results.jsonl into results/kifmm-COMMIT.jsonl (the report compares them), then
#   `run.sh --solvers kifmm` (same data and reference files: the work directory of the build).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
profile=full
build="${KIFMM_BUILD_DIR:-$root/build}"
out="" doc="" full="" bin="" only="" maxn="" minn="" force="" report_only=0 commit="" solvers="" timeout=""
threads="${OMP_NUM_THREADS:-1}"
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) profile=quick ;;
    --tiny) profile=tiny ;;
    --out) out="$2"; shift ;;
    --doc) doc="$2"; shift ;;
    --full) full="$2"; shift ;;
    --build) build="$2"; shift ;;
    --bin) bin="$2"; shift ;;
    --only) only="$2"; shift ;;
    --max-n) maxn="$2"; shift ;;
    --min-n) minn="$2"; shift ;;
    --threads) threads="$2"; shift ;;
    --force) force=--force ;;
    --report-only) report_only=1 ;;
    --commit) commit="$2"; shift ;;
    --solvers) solvers="$2"; shift ;;
    --timeout) timeout="$2"; shift ;;
    *) echo "run.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [ "$profile" = full ]; then
  out="${out:-$here/results}"
  doc="${doc:-$root/doc/benchmarks.md}"
  full="${full:-$out/full_report.md}"
else
  out="${out:-$build/bench_solvers_$profile}"
  doc="${doc:-$out/summary.md}"
  full="${full:-$out/full_report.md}"
fi
mkdir -p "$out"
work="$out/work"
[ "$profile" = full ] && work="$build/bench_solvers_work"

# Debian's python3 has matplotlib; a python3 earlier in PATH may not
py=python3
for cand in /usr/bin/python3 python3; do
  if command -v "$cand" >/dev/null && "$cand" -c "import matplotlib" 2>/dev/null; then
    py="$cand"; break
  fi
done

if [ "$report_only" = 0 ]; then
  if [ -z "$bin" ]; then
    if [ ! -f "$build/CMakeCache.txt" ]; then cmake -S "$root" -B "$build" >/dev/null; fi
    make -C "$build" -j2 bench_solvers lmp_kifmm >/dev/null
    bin="$build/bench_solvers"
  fi
  lmp="$(dirname "$bin")/lmp_kifmm"    # runs the example scenes for their snapshots
  if [ -z "$commit" ]; then
    commit="$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
    if [ -n "$(git -C "$root" status --porcelain -- src 2>/dev/null)" ]; then commit="$commit+dirty"; fi
  fi
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
  "$py" "$here/run_bench.py" --profile "$profile" --bin "$bin" --work "$work" \
    --results "$out/results.jsonl" --threads "$threads" --commit "$commit" --lmp "$lmp" ${only:+--only "$only"} \
    ${maxn:+--max-n "$maxn"} ${minn:+--min-n "$minn"} ${solvers:+--solvers "$solvers"} ${timeout:+--timeout "$timeout"} \
    $force
fi
"$py" "$here/report.py" --profile "$profile" --results "$out/results.jsonl" --plots "$out" \
  --doc "$doc" --full "$full"
echo "report: $doc, full tables: $full (plots and results in $out)"
