#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Installs what lammps-kifmm needs from Debian's packages, only what is missing.
# Idempotent and non-interactive; used by both README commands and by CI.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  lammps liblammps-dev python3-lammps
  libopenmpi-dev openmpi-bin
  libfftw3-dev libeigen3-dev libfmt-dev libgtest-dev
  googletest libyaml-dev libpng-dev libjpeg-dev zlib1g-dev
  python3 python3-matplotlib python3-numpy
  clang libclang-rt-dev
)
# extra packages for optional tools: KIFMM_SETUP_EXTRA="valgrind clang ..."
if [ -n "${KIFMM_SETUP_EXTRA:-}" ]; then
  read -r -a extra <<< "$KIFMM_SETUP_EXTRA"
  packages+=("${extra[@]}")
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
