#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Builds a current LAMMPS from a source tarball, once per machine, to run the plugin in it:
# lmp with a shared liblammps and the packages the package's tests and examples need (PLUGIN
# GRANULAR KSPACE RIGID MOLECULE EXTRA-FIX GRAPHICS DIPOLE), and LAMMPS's force-style test
# runners (test_pair_style, test_fix_timestep). The build lives outside the checkout, in
# $KIFMM_LAMMPS_CACHE (default ~/.cache/lammps-kifmm/lammps), in a directory named by the
# SHA256 of the tarball and of the build settings below, so it is reused until either changes. Prints the
# build directory (lmp, liblammps.so, unittest/force-styles/test_*; the sources are in
# <dir>/source) on its last line.
#
# Usage: bash tools/build-lammps.sh [lammps-SOURCE.tar.gz]
#   default tarball: $KIFMM_LAMMPS_TARBALL, else ../shared/lammps/lammps-*.tar.gz beside the
#   checkout. KIFMM_LAMMPS_JOBS (default nproc) parallel compile jobs.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tarball="${1:-${KIFMM_LAMMPS_TARBALL:-}}"
if [ -z "$tarball" ]; then
  for t in "$root"/../shared/lammps/lammps-*.tar.gz; do [ -f "$t" ] && tarball="$t"; done
fi
if [ -z "$tarball" ] || [ ! -f "$tarball" ]; then
  echo "build-lammps: no LAMMPS source tarball (give its path, or set KIFMM_LAMMPS_TARBALL)" >&2
  exit 2
fi
tarball="$(cd "$(dirname "$tarball")" && pwd)/$(basename "$tarball")"
bash "$root/tools/setup.sh" >&2

# what the build depends on: the tarball and these settings (-O1: the LAMMPS core is not what
# is measured here, the plugin has its own flags; it halves the compile time of -O2)
settings=(-D CMAKE_BUILD_TYPE=Release -D CMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG"
  -D BUILD_SHARED_LIBS=on -D BUILD_MPI=on -D BUILD_OMP=on -D LAMMPS_INSTALL_RPATH=on
  -D PKG_PLUGIN=on -D PKG_GRANULAR=on -D PKG_KSPACE=on -D PKG_RIGID=on -D PKG_MOLECULE=on
  -D PKG_EXTRA-FIX=on -D PKG_GRAPHICS=on -D PKG_DIPOLE=on -D FFT=FFTW3 -D ENABLE_TESTING=on)
targets=(lmp test_pair_style test_fix_timestep)
key=$( (sha256sum < "$tarball"; echo "${settings[*]} ${targets[*]}") | sha256sum | cut -c1-16)
home="${HOME:-$(getent passwd "$(id -u)" | cut -d: -f6)}"
cache="${KIFMM_LAMMPS_CACHE:-${XDG_CACHE_HOME:-${home:-/var/tmp}/.cache}/lammps-kifmm/lammps}"
dir="$cache/$key"
if [ -f "$dir/build.done" ]; then
  echo "build-lammps: using the cached build of $(basename "$tarball")" >&2
  echo "$dir"
  exit 0
fi

echo "build-lammps: building LAMMPS from $(basename "$tarball") into $dir (once per machine)" >&2
rm -rf "$dir"
mkdir -p "$dir/source"
tar -xzf "$tarball" -C "$dir/source" --strip-components=1

# LAMMPS's unit tests build googletest from an archive; Debian's googletest sources serve
mkdir -p "$dir/_deps"
tar -czf "$dir/_deps/googletest-debian.tar.gz" -C /usr/src --transform 's,^googletest,googletest-debian,' googletest
gtest_sha=$(sha256sum "$dir/_deps/googletest-debian.tar.gz" | cut -d' ' -f1)

cmake -S "$dir/source/cmake" -B "$dir" "${settings[@]}" \
  -D GTEST_URL="file://$dir/_deps/googletest-debian.tar.gz" -D GTEST_SHA256="$gtest_sha" \
  > "$dir/configure.log" 2>&1 || { tail -30 "$dir/configure.log" >&2; exit 1; }
jobs="${KIFMM_LAMMPS_JOBS:-$(nproc)}"
cmake --build "$dir" -j "$jobs" --target "${targets[@]}" > "$dir/build.log" 2>&1 \
  || { tail -30 "$dir/build.log" >&2; exit 1; }
"$dir/lmp" -h > "$dir/lmp-help.txt"
touch "$dir/build.done"
echo "$dir"
