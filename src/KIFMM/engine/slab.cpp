// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Doubly periodic (slab, p p f) reference sum: slab_direct_sum (periodic.h) by the Ewald split of
// slab_ewald.h.
#include "periodic.h"
#include "slab_ewald.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

namespace kifmm {

using namespace ewald;

void slab_direct_sum(const double center[3], double h, const double *shape, std::size_t n_src, const double *src_xyz,
                     const double *src_q, std::size_t n_trg, const double *trg_xyz, double *pot, double *grad)
{
  const double one[3] = {1.0, 1.0, 1.0};
  const double *sh = shape ? shape : one;
  const SlabSplit s(sh);
  auto unit = [&](std::size_t n, const double *xyz, std::vector<double> &u) {
    u.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) {
        double x = (xyz[3 * i + d] - center[d]) / h;
        if (d < 2) x -= s.period[d] * std::floor((x + sh[d]) / s.period[d]);    // into [-shape, shape)
        u[3 * i + d] = x;
      }
  };
  std::vector<double> su, tu;
  unit(n_src, src_xyz, su);
  unit(n_trg, trg_xyz, tu);
  // reciprocal vectors of a half plane (the +-m pairs once, weight doubled)
  struct KVec {
    int mx, my;
    double k;
  };
  std::vector<KVec> ks;
  const int Kx = s.kmax_axis(0), Ky = s.kmax_axis(1);
  for (int mx = 0; mx <= Kx; ++mx)
    for (int my = -Ky; my <= Ky; ++my) {
      if (mx == 0 && my <= 0) continue;
      const double k = s.k_of(mx, my);
      if (k > 0) ks.push_back({mx, my, k});
    }
#pragma omp parallel for schedule(dynamic, 4)
  for (std::size_t i = 0; i < n_trg; ++i) {
    double v = 0, g[3] = {0, 0, 0};
    for (std::size_t j = 0; j < n_src; ++j) {
      const double q = src_q[j];
      if (q == 0.0) continue;
      double r[3];
      for (int d = 0; d < 3; ++d) r[d] = tu[3 * i + d] - su[3 * j + d];
      for (int d = 0; d < 2; ++d) r[d] -= s.period[d] * std::nearbyint(r[d] / s.period[d]);
      const bool same = r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0;
      // real space over the x-y images
      const int N0 = s.images(0, std::fabs(r[0])), N1 = s.images(1, std::fabs(r[1]));
      for (int a = -N0; a <= N0; ++a)
        for (int b = -N1; b <= N1; ++b) {
          const double d[3] = {r[0] + s.period[0] * a, r[1] + s.period[1] * b, r[2]};
          const double rr = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
          const bool zero = a == 0 && b == 0;
          if (rr == 0.0) {
            if (zero && same) v += q * s.reg0();
            continue;
          }
          if (rr > s.real_cut() && !(zero && same)) continue;
          double t, F;
          s.real(rr, zero && same, t, F);
          v += q * t;
          for (int c = 0; c < 3; ++c) g[c] += q * F * d[c];
        }
      // reciprocal space: cos(k.rho) w(k, z), and the k = 0 term
      for (const KVec &kv : ks) {
        const double kx = kPi * kv.mx / sh[0], ky = kPi * kv.my / sh[1];
        const double ph = kx * r[0] + ky * r[1];
        double w, dw;
        s.weight(kv.k, r[2], w, dw);
        const double c = std::cos(ph), sn = std::sin(ph);
        v += 2 * q * w * c;
        g[0] -= 2 * q * w * kx * sn;
        g[1] -= 2 * q * w * ky * sn;
        g[2] += 2 * q * dw * c;
      }
      double z0, dz0;
      s.zero_term(r[2], z0, dz0);
      v += q * z0;
      g[2] += q * dz0;
    }
    if (pot) pot[i] = v / h;
    if (grad)
      for (int d = 0; d < 3; ++d) grad[3 * i + d] = g[d] / (h * h);
  }
}

void slab_gradient_via_3d(const double center[3], double h, const double *shape, std::size_t n_src,
                          const double *src_xyz, const double *src_q, std::size_t n_trg, const double *trg_xyz,
                          double *grad)
{
  const double one[3] = {1.0, 1.0, 1.0};
  const double *sh = shape ? shape : one;
  const double hw[3] = {h * sh[0], h * sh[1], h * sh[2]};
  const double Hz = hw[2] + 4.0 * std::max(hw[0], hw[1]);    // vacuum 2 (Hz - hz) = 8 max half-width
  const double H = std::max(std::max(hw[0], hw[1]), Hz);
  const double s3[3] = {hw[0] / H, hw[1] / H, Hz / H};
  // points wrapped in x and y only (z stays inside the slab)
  std::vector<double> su(3 * n_src), tu(3 * n_trg);
  for (std::size_t i = 0; i < n_src; ++i)
    for (int d = 0; d < 3; ++d) su[3 * i + d] = src_xyz[3 * i + d];
  for (std::size_t i = 0; i < n_trg; ++i)
    for (int d = 0; d < 3; ++d) tu[3 * i + d] = trg_xyz[3 * i + d];
  periodic_direct_sum(KernelSpec{}, center, H, n_src, su.data(), src_q, n_trg, tu.data(), nullptr, grad, s3);
  double Q = 0, Mz = 0;
  for (std::size_t j = 0; j < n_src; ++j) {
    Q += src_q[j];
    Mz += src_q[j] * (src_xyz[3 * j + 2] - center[2]);
  }
  const double V = 8.0 * hw[0] * hw[1] * Hz;
  for (std::size_t i = 0; i < n_trg; ++i) grad[3 * i + 2] += 4 * kPi / V * (Mz - Q * (trg_xyz[3 * i + 2] - center[2]));
}

}    // namespace kifmm
