#!/usr/bin/env bash
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
# Installs what the anchor benchmark needs besides the project's own packages (Debian
# packages only, only what is missing): OpenBLAS (BLAS and LAPACK of PVFMM and exafmm-t).
# MPI and FFTW come with tools/setup.sh.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
KIFMM_SETUP_EXTRA="libopenblas-dev ${KIFMM_SETUP_EXTRA:-}" exec bash "$here/../../tools/setup.sh"
