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

// Charges and dipoles (evaluate_dipoles conventions): sources with q == 0 and mu == 0 skipped.
template <class K>
std::size_t direct_sum_dipoles_t(const K &k, std::size_t n_src, const double *src_xyz, const double *src_q,
                                 const double *src_mu, std::size_t n_trg, const double *trg_xyz, double *pot,
                                 double *grad, double *hess)
{
  std::vector<double> s[7];    // x y z q mx my mz
  for (std::size_t j = 0; j < n_src; ++j) {
    const double q = src_q ? src_q[j] : 0.0;
    const double *m = src_mu ? src_mu + 3 * j : nullptr;
    if (q == 0.0 && (!m || (m[0] == 0.0 && m[1] == 0.0 && m[2] == 0.0))) continue;
    for (int d = 0; d < 3; ++d) s[d].push_back(src_xyz[3 * j + d]);
    s[3].push_back(q);
    for (int d = 0; d < 3; ++d) s[4 + d].push_back(m ? m[d] : 0.0);
  }
  const std::size_t ns = s[0].size();
  std::size_t zeros = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : zeros)
  for (std::size_t i = 0; i < n_trg; ++i) {
    double x[3] = {trg_xyz[3 * i], trg_xyz[3 * i + 1], trg_xyz[3 * i + 2]}, p = 0, g[3] = {}, h[6] = {};
    const PointSpan trg{1, &x[0], &x[1], &x[2], nullptr};
    const PointSpan src{ns, s[0].data(), s[1].data(), s[2].data(), s[3].data(),
                        src_mu ? s[4].data() : nullptr, s[5].data(), s[6].data()};
    ResultSpan res{&p, &g[0], &g[1], &g[2]};
    if (hess) res = {&p, &g[0], &g[1], &g[2], &h[0], &h[1], &h[2], &h[3], &h[4], &h[5]};
    std::size_t z = 0;
    p2p_dipole<K, true, true, true>(k, trg, src, res, &z);
    zeros += z;
    if (pot) pot[i] = p;
    if (grad)
      for (int d = 0; d < 3; ++d) grad[3 * i + d] = g[d];
    if (hess)
      for (int c = 0; c < 6; ++c) hess[6 * i + c] = h[c];
  }
  return zeros;
}

}    // namespace kifmm
