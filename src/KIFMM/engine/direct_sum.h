// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Templated exact O(N*M) sum (OpenMP over target blocks, vectorized p2p over source chunks);
// the non-template entry kifmm::direct_sum (kifmm.h) dispatches on KernelSpec.
#pragma once

#include "p2p.h"

#include <algorithm>
#include <cstddef>
#include <vector>

namespace kifmm {

// Returns the number of r = 0 pairs met (self pairs included).
template <class K>
std::size_t direct_sum_t(const K &k, std::size_t n_src, const double *src_xyz, const double *src_q,
                         std::size_t n_trg, const double *trg_xyz, double *pot, double *grad)
{
  std::vector<double> sx, sy, sz, sq;
  sx.reserve(n_src);
  sy.reserve(n_src);
  sz.reserve(n_src);
  sq.reserve(n_src);
  for (std::size_t j = 0; j < n_src; ++j) {
    if (src_q[j] == 0.0) continue;
    sx.push_back(src_xyz[3 * j]);
    sy.push_back(src_xyz[3 * j + 1]);
    sz.push_back(src_xyz[3 * j + 2]);
    sq.push_back(src_q[j]);
  }
  const std::size_t ns = sx.size();
  constexpr std::size_t kTB = 64, kSB = 8192;
  const std::size_t nblk = (n_trg + kTB - 1) / kTB;
  std::size_t zeros = 0;
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : zeros)
  for (std::size_t b = 0; b < nblk; ++b) {
    const std::size_t i0 = b * kTB, nt = std::min(kTB, n_trg - i0);
    double tx[kTB], ty[kTB], tz[kTB], p[kTB] = {}, gx[kTB] = {}, gy[kTB] = {}, gz[kTB] = {};
    for (std::size_t i = 0; i < nt; ++i) {
      tx[i] = trg_xyz[3 * (i0 + i)];
      ty[i] = trg_xyz[3 * (i0 + i) + 1];
      tz[i] = trg_xyz[3 * (i0 + i) + 2];
    }
    std::size_t z = 0;
    const PointSpan trg{nt, tx, ty, tz, nullptr};
    const ResultSpan res{p, gx, gy, gz};
    for (std::size_t j0 = 0; j0 < ns; j0 += kSB) {
      const PointSpan src{std::min(kSB, ns - j0), &sx[j0], &sy[j0], &sz[j0], &sq[j0]};
      if (grad)
        p2p_pg<K, true>(k, pot != nullptr, trg, src, res, &z);
      else if (pot)
        p2p<K, true, false, true>(k, trg, src, res, &z);
    }
    zeros += z;
    for (std::size_t i = 0; i < nt; ++i) {
      if (pot) pot[i0 + i] = p[i];
      if (grad) {
        grad[3 * (i0 + i)] = gx[i];
        grad[3 * (i0 + i) + 1] = gy[i];
        grad[3 * (i0 + i) + 2] = gz[i];
      }
    }
  }
  return zeros;
}

}    // namespace kifmm
