#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Benchmark of our engine against PVFMM and exafmm-t (README.md beside this file).
#   bash bench/anchors/run.sh [BUILD_DIR]        (default build-anchors, relative to the checkout)
# The anchors' source trees are given once, when the build directory is configured:
#   PVFMM_SOURCE_DIR=/path/to/pvfmm EXAFMMT_SOURCE_DIR=/path/to/exafmm-t bash bench/anchors/run.sh
# (either or both; later runs take them from the build directory). Prints a markdown table and
# writes it, with provenance, to bench/anchors/results/.
# Settings (environment): OMP_NUM_THREADS (1; above 1 the settings are chosen and compared by wall
# time, else by CPU time), ANCHORS_SETS ("uniform:1e5 plummer:1e5 uniform:1e6"),
# ANCHORS_TARGETS ("1e-5 1e-7 1e-10"), ANCHORS_ROUNDS (3; timed rounds), ANCHORS_ROUNDS_LARGE (2; for
# N >= 1e6), the sweeps OURS_ACC, OURS_LEAVES, PVFMM_ORDERS, PVFMM_LEAVES, EXAFMMT_ORDERS,
# EXAFMMT_LEAVES (and *_LEAVES_LARGE for N >= 1e6), KIFMM_JOBS (2; build jobs).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
command_line="bash bench/anchors/run.sh${*:+ $*}"
build="${1:-build-anchors}"

sets="${ANCHORS_SETS:-uniform:1e5 plummer:1e5 uniform:1e6}"
targets="${ANCHORS_TARGETS:-1e-5 1e-7 1e-10}"
rounds="${ANCHORS_ROUNDS:-3}"
rounds_large="${ANCHORS_ROUNDS_LARGE:-2}"
ours_acc="${OURS_ACC:-1e-5 3e-6 1e-7 3e-8 1e-10 3e-11}"
ours_leaves="${OURS_LEAVES:-60 150 500}"
ours_leaves_large="${OURS_LEAVES_LARGE:-}"
pvfmm_orders="${PVFMM_ORDERS:-4 6 8 10 12 14}"
pvfmm_leaves="${PVFMM_LEAVES:-300 450 600}"
pvfmm_leaves_large="${PVFMM_LEAVES_LARGE:-300 600}"
exafmmt_orders="${EXAFMMT_ORDERS:-5 6 7 8 9 10 11 12 13 14}"
exafmmt_leaves="${EXAFMMT_LEAVES:-64 128 256 400}"
exafmmt_leaves_large="${EXAFMMT_LEAVES_LARGE:-64 400}"
threads="${OMP_NUM_THREADS:-1}"
export OMP_NUM_THREADS="$threads" OPENBLAS_NUM_THREADS="$threads"
# the time compared: CPU time on one thread, wall time on more (table.py)
if [ "$threads" -gt 1 ]; then export ANCHORS_TIME=wall; else export ANCHORS_TIME=cpu; fi

# ---- the build: the anchors' sources from the environment or the build directory's cache
cached() { [ -f "$build/CMakeCache.txt" ] && sed -n "s/^$1:[A-Z]*=//p" "$build/CMakeCache.txt" || true; }
pvfmm_src="${PVFMM_SOURCE_DIR:-$(cached PVFMM_SOURCE_DIR)}"
exafmmt_src="${EXAFMMT_SOURCE_DIR:-$(cached EXAFMMT_SOURCE_DIR)}"
if [ -z "$pvfmm_src" ] && [ -z "$exafmmt_src" ]; then
  cat >&2 <<HELP
run.sh: the anchors' source trees are not given. Fetch them (see bench/anchors/README.md):
  git clone --recursive https://github.com/dmalhotra/pvfmm.git /path/to/pvfmm
  git clone https://github.com/exafmm/exafmm-t.git /path/to/exafmm-t
  bash bench/anchors/setup.sh        # OpenBLAS (Debian packages)
then run, either or both:
  PVFMM_SOURCE_DIR=/path/to/pvfmm EXAFMMT_SOURCE_DIR=/path/to/exafmm-t bash bench/anchors/run.sh ${1:-}
HELP
  exit 1
fi
cmake_args=(-DCMAKE_BUILD_TYPE=Release -DKIFMM_ENGINE_ONLY=ON)
targets_build=(anchors_points anchors_ours)
[ -n "$pvfmm_src" ] && cmake_args+=("-DPVFMM_SOURCE_DIR=$pvfmm_src") && targets_build+=(anchors_pvfmm)
[ -n "$exafmmt_src" ] && cmake_args+=("-DEXAFMMT_SOURCE_DIR=$exafmmt_src") && targets_build+=(anchors_exafmmt)
echo "run.sh: building ${targets_build[*]} in $build" >&2
mkdir -p "$build"
nice -n 10 cmake -S "$root" -B "$build" "${cmake_args[@]}" >"$build/anchors-cmake.log" 2>&1 ||
  { cat "$build/anchors-cmake.log" >&2; exit 1; }
nice -n 10 cmake --build "$build" -j "${KIFMM_JOBS:-2}" --target "${targets_build[@]}" >"$build/anchors-build.log" 2>&1 ||
  { tail -30 "$build/anchors-build.log" >&2; exit 1; }
bin="$build/bench/anchors"
codes=(ours)
[ -n "$pvfmm_src" ] && codes+=(pvfmm)
[ -n "$exafmmt_src" ] && codes+=(exafmmt)

# ---- problems and operator caches (PVFMM's operator files, exafmm-t's matrices; not timed)
data="$build/anchors-data"
mkdir -p "$data/cache" bench/anchors/results
PVFMM_DIR="$(cd "$data/cache" && pwd)"
export PVFMM_DIR
stamp="$(date -u +%Y%m%dT%H%M%SZ)"
raw="$data/rows_$stamp.txt"
: >"$raw"
load_before="$(cat /proc/loadavg)"
started="$(date -u '+%Y-%m-%d %H:%M:%S UTC')"
for s in $sets; do
  name="${s%%:*}" n="${s##*:}"
  f="$data/${name}_$n.bin"
  [ -f "$f" ] || "$bin/anchors_points" "$name" "$n" "$f" >&2
done

is_large() { python3 -c "import sys; sys.exit(0 if float('$1') >= 1e6 else 1)"; }
join() { local IFS=,; echo "$*"; }
# settings of a code for a sweep: order or accuracy x leaf size
grid() {    # ORDERS LEAVES [AUTO]: "o:l,..." (AUTO: also each order alone)
  local out=() o l
  for o in $1; do
    [ -n "${3:-}" ] && out+=("$o")
    for l in $2; do out+=("$o:$l"); done
  done
  join "${out[@]}"
}
run_code() {    # CODE SET N ROUND WARMUP SETTINGS
  local exe
  case "$1" in ours) exe=anchors_ours ;; pvfmm) exe=anchors_pvfmm ;; exafmmt) exe=anchors_exafmmt ;; esac
  echo "run.sh: round $4 $2 $3 $1 ($6)" >&2
  "$bin/$exe" "$data/${2}_$3.bin" --settings "$6" --reps 1 --warmup "$5" --cache "$data/cache" 2>>"$data/stderr_$stamp.txt" |
    awk -v r="$4" '$1 == "ROW" { print "round=" r, $0 }' >>"$raw" ||
    echo "run.sh: $exe failed on $2 $3 (see $data/stderr_$stamp.txt)" >&2
}
# the next order of a list after each of the given ones, and those
widen() {    # LIST SELECTED
  python3 - "$1" "$2" <<'PY'
import sys
lst = [int(x) for x in sys.argv[1].split()]
sel = sorted({int(x) for x in sys.argv[2].split()})
out = set()
for o in sel:
    out.add(o)
    up = [x for x in lst if x > o]
    if up: out.add(up[0])
print(" ".join(str(x) for x in sorted(out)))
PY
}

# ---- round 0: the sweep of each code's settings (one evaluation each, no warm-up), from which
# each code's cheapest setting (CPU time) meeting each target error is taken
for s in $sets; do
  name="${s%%:*}" n="${s##*:}"
  if is_large "$n"; then
    ol="$ours_leaves_large" pl="$pvfmm_leaves_large" el="$exafmmt_leaves_large"
    # the orders selected at uniform 1e5 (when measured) and the next one
    sel="$(python3 bench/anchors/table.py orders "$raw" uniform 1e5 $targets)"
    po="$(echo "$sel" | awk '$1 == "pvfmm" { print $2 }' | tr '\n' ' ')"
    eo="$(echo "$sel" | awk '$1 == "exafmmt" { print $2 }' | tr '\n' ' ')"
    po="$( [ -n "$po" ] && widen "$pvfmm_orders" "$po" || echo "$pvfmm_orders")"
    eo="$( [ -n "$eo" ] && widen "$exafmmt_orders" "$eo" || echo "$exafmmt_orders")"
  else
    ol="$ours_leaves" pl="$pvfmm_leaves" el="$exafmmt_leaves" po="$pvfmm_orders" eo="$exafmmt_orders"
  fi
  for c in "${codes[@]}"; do
    case "$c" in
      ours) run_code ours "$name" "$n" 0 0 "$(grid "$ours_acc" "$ol" auto)" ;;
      pvfmm) run_code pvfmm "$name" "$n" 0 0 "$(grid "$po" "$pl")" ;;
      exafmmt) run_code exafmmt "$name" "$n" 0 0 "$(grid "$eo" "$el")" ;;
    esac
  done
done

# ---- timed rounds: the selected settings, codes interleaved (ours, PVFMM, exafmm-t) in each round
declare -A chosen
for s in $sets; do
  name="${s%%:*}" n="${s##*:}"
  while read -r code t setting; do
    [ "$code" = ours_leaf ] && code=ours
    args="$(echo "$setting" | sed -E 's/^[a-z_]+//; s/:[a-z_]+/:/')"
    case ",${chosen[$s.$code]:-}," in *",$args,"*) ;; *) chosen[$s.$code]="${chosen[$s.$code]:+${chosen[$s.$code]},}$args" ;; esac
  done < <(python3 bench/anchors/table.py select "$raw" "$name" "$n" $targets)
done
max_rounds=$(( rounds > rounds_large ? rounds : rounds_large ))
for ((r = 1; r <= max_rounds; ++r)); do
  for s in $sets; do
    name="${s%%:*}" n="${s##*:}"
    if is_large "$n"; then [ "$r" -le "$rounds_large" ] || continue; else [ "$r" -le "$rounds" ] || continue; fi
    for c in "${codes[@]}"; do
      [ -n "${chosen[$s.$c]:-}" ] && run_code "$c" "$name" "$n" "$r" 1 "${chosen[$s.$c]}"
    done
  done
done
load_after="$(cat /proc/loadavg)"

# ---- the report
commit_of() { git -C "$1" rev-parse HEAD 2>/dev/null || echo unknown; }
ours_commit="$(git rev-parse HEAD)$(git diff --quiet HEAD -- . 2>/dev/null || echo ' (with uncommitted changes)')"
out="bench/anchors/results/anchors_$(git rev-parse --short HEAD)_$stamp.md"
{
  echo "# Anchor benchmark: ours vs PVFMM and exafmm-t"
  echo
  echo "- command: \`OMP_NUM_THREADS=$threads $command_line\`"
  echo "- date: $started to $(date -u '+%H:%M:%S UTC')"
  echo "- our commit: $ours_commit"
  [ -n "$pvfmm_src" ] && echo "- PVFMM commit: $(commit_of "$pvfmm_src") (SCTL $(commit_of "$pvfmm_src/SCTL"))"
  [ -n "$exafmmt_src" ] && echo "- exafmm-t commit: $(commit_of "$exafmmt_src")"
  echo "- machine: \`$(uname -a)\`, nproc $(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc), $(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')"
  echo "- load average before: $load_before; after: $load_after"
  echo "- threads: OMP_NUM_THREADS=$threads (OPENBLAS_NUM_THREADS=$threads), one MPI process (PVFMM); time compared: $ANCHORS_TIME"
  echo "- compiler: $(c++ --version | head -1); ours: -O3 -march=native -mprefer-vector-width=512" \
       "-fno-math-errno; PVFMM, exafmm-t: -O3 -march=native, OpenBLAS $(dpkg-query -W -f='${Version}' libopenblas-dev 2>/dev/null || echo '?'), FFTW"
  echo "- timed rounds: $rounds (N >= 1e6: $rounds_large), each after the sweep (round 0) that chose the settings"
  echo "- sweeps: ours accuracies {$ours_acc}, leaves {$ours_leaves} (N >= 1e6: {$ours_leaves_large});" \
       "PVFMM m {$pvfmm_orders}, max_pts {$pvfmm_leaves} (N >= 1e6: {$pvfmm_leaves_large});" \
       "exafmm-t p {$exafmmt_orders}, ncrit {$exafmmt_leaves} (N >= 1e6: {$exafmmt_leaves_large});" \
       "at N >= 1e6 the anchors' orders are those chosen at uniform 1e5 and the next one"
  echo
  python3 bench/anchors/table.py table "$raw" $targets
  echo
  echo "All rows (round 0 = sweep):"
  echo
  echo '```'
  cat "$raw"
  echo '```'
} >"$out"
python3 bench/anchors/table.py table "$raw" $targets
echo
echo "run.sh: written $out" >&2
