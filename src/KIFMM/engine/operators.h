// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Precomputed translation operators of one unit box (half-width 1, center 0) for one unit
// kernel (kernel_scaling.h) and order p. Physical use at half-width h with scale s
// (G(h u) = s G_unit(u)):
//   P2M : equiv = (1/s) UC2E * (physical check potential of the sources)
//   M2M : parent equiv += M2M[oct] * child equiv            (s cancels)
//   M2L : check += s * conv(M2L kernel, equiv)              (m2l_fft.h)
//   L2L : child check += s * L2L[oct] * parent equiv
//   L2L/P2L/M2L check -> down equiv: equiv = (1/s) DC2E * check
// Pseudo-inverses are kept as two factors A * (B * x) (A = V S^+, B = U^T), with a relative
// singular-value cutoff, as in exafmm-t; this stays stable up to p = 14.
#pragma once

#include "kernel_scaling.h"

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace kifmm {

constexpr int kOperatorVersion = 3;    // bump when the operator layout or math changes

struct OperatorSet {
  int p = 0, nsurf = 0, rank = 0, nfreq = 0;
  std::string id;                                    // unit kernel id
  std::vector<double> uc2e_a, uc2e_b;                // nsurf x rank, rank x nsurf (row-major)
  std::vector<double> dc2e_a, dc2e_b;
  std::array<std::vector<double>, 8> m2m, l2l;       // nsurf x nsurf (row-major)
  std::vector<double> m2l_hat;                       // 316 kernel spectra, block-major (m2l_fft.h)
  std::size_t bytes() const;
};

// Relative cutoff on singular values of the check-to-equivalent matrix.
double pinv_relative_cutoff(int p);

// Compute every operator (cold path: SVD + kernel FFTs).
std::shared_ptr<OperatorSet> compute_operators(const UnitKernel &k, int p);

// y (+)= M x for a row-major rows x cols matrix (Eigen, vectorized).
void matvec(const double *M, int rows, int cols, const double *x, double *y, double alpha, bool accumulate);
// equiv = alpha * A (B x) for the two-factor pseudo-inverse.
void apply_pinv(const std::vector<double> &A, const std::vector<double> &B, int nsurf, int rank,
                const double *check, double *equiv, double alpha, double *scratch);

// Batched forms on m column vectors stored contiguously (column-major rows x m):
// Y (+)= alpha * M X, and EQ = alpha * A (B CHK).
void matmat(const double *M, int rows, int cols, const double *X, int m, double *Y, double alpha, bool accumulate);
void apply_pinv_batch(const std::vector<double> &A, const std::vector<double> &B, int nsurf, int rank,
                      const double *check, int m, double *equiv, double alpha);

}    // namespace kifmm
