#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Builds the libFuzzer targets with clang (ASan + UBSan) and runs each for a short time.
# Usage: fuzz/run-fuzz.sh [SECONDS_PER_TARGET]   (CI runs it briefly through ctest, label fuzz)
# A crash leaves its input in fuzz/out/: add it to a regression test, then to the corpus.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
secs="${1:-20}"
out="${KIFMM_FUZZ_DIR:-$root/build/fuzz}"
mkdir -p "$out"
CXX="${FUZZ_CXX:-clang++}"
flags="-std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined"
status=0
build_and_run() {
  local name="$1"; shift
  "$CXX" $flags -I"$root/src/KIFMM" -I"$root/src/RIGID_CLUMP" "$@" -o "$out/$name"
  mkdir -p "$out/corpus-$name"
  cp -n "$root/fuzz/corpus/$name/"* "$out/corpus-$name/" 2>/dev/null || true
  local dict=()
  [ -e "$root/fuzz/$name.dict" ] && dict=(-dict="$root/fuzz/$name.dict")
  if ! (cd "$out" && "./$name" -max_total_time="$secs" -timeout=20 -max_len=8192 \
        "${dict[@]}" -print_final_stats=1 "corpus-$name" \
        > "$name.log" 2>&1); then
    echo "fuzz: $name FAILED (see $out/$name.log and the crash-* file there)"; tail -30 "$out/$name.log"
    status=1
  else
    echo "fuzz: $name ran ${secs}s: $(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$out/$name.log")"
  fi
}
build_and_run kifmm_keywords "$root/fuzz/fuzz_kifmm_keywords.cpp" "$root/src/KIFMM/kifmm_keywords.cpp"
for target in "$root"/fuzz/fuzz_clump_*.cpp; do
  [ -e "$target" ] || continue
  name="$(basename "$target" .cpp)"; name="${name#fuzz_}"
  build_and_run "$name" "$target" "$root/src/RIGID_CLUMP/clump_template.cpp" \
    "$root/src/RIGID_CLUMP/clump_union.cpp" ${KIFMM_FUZZ_EXTRA_SOURCES:-}
done
exit $status
