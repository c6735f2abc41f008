// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Ewald split of the lattice sum of the unit cell (half-width 1, period 2; or a rectangular
// unit cell of half-widths shape[d], largest 1, periods 2 shape[d]) for the Laplace (tin-foil,
// k = 0 omitted, uniform background) and Yukawa kernels: real-space terms with erfc,
// reciprocal weights, background constant (internal to periodic.cpp and periodic_grid.cpp).
#pragma once

#include "kifmm.h"

#include <algorithm>
#include <cmath>

namespace kifmm::ewald {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSqrtPi = 1.77245385090551602729;
constexpr double kPeriod = 2.0;                    // unit cube: half-width 1
constexpr double kVolume = 8.0;
constexpr double kRealCut = 2.3;                   // Ewald real-space terms beyond: < exp(-47)

// Laplace real-space term of the split with parameter alpha: phi(r) = erfc(alpha r) / r and
// F = phi'(r) / r; reg: phi minus the bare 1/r (shared with slab_ewald.h).
inline void laplace_real(double alpha, double r, bool reg, double &v, double &F)
{
  const double ar = alpha * r;
  const double gauss = (2 * alpha / kSqrtPi) * std::exp(-ar * ar);
  if (reg) {
    v = -std::erf(ar) / r;
    F = (std::erf(ar) / (r * r) - gauss / r) / r;
  } else {
    v = std::erfc(ar) / r;
    F = (-std::erfc(ar) / (r * r) - gauss / r) / r;
  }
}

// Ewald split (or direct image sum) of the unit-cell lattice sum of one kernel.
struct Split {
  bool yukawa = false, direct = false;
  double kappa = 0, alpha = 3.0, a = 0;    // a = kappa / (2 alpha)
  int nreal = 2, kmax = 13;
  double shape[3] = {1.0, 1.0, 1.0};         // half-widths of the unit cell
  double period[3] = {kPeriod, kPeriod, kPeriod};
  double volume = kVolume;

  explicit Split(const KernelSpec &k, const double *cell_shape = nullptr)
  {
    yukawa = k.type == KernelType::Yukawa;
    kappa = yukawa ? k.kappa : 0.0;
    // images beyond |n| = 2 are > 3.9 away: exp(-kappa 3.9) < 1e-17 for kappa >= 10
    direct = yukawa && kappa >= 10.0;
    a = kappa / (2 * alpha);
    if (cell_shape) {
      volume = 1.0;
      for (int d = 0; d < 3; ++d) {
        shape[d] = cell_shape[d];
        period[d] = 2.0 * cell_shape[d];
        volume *= period[d];
      }
      // the split scaled with the shortest edge (real-space images within a few short periods,
      // reciprocal vectors up to the same |k| per short axis): the cube's split for cubes
      smin = std::min(shape[0], std::min(shape[1], shape[2]));
      alpha /= smin;
      kmax = (int) std::ceil(kmax / smin - 1e-9);
      a = kappa / (2 * alpha);
    }
  }
  double smin = 1.0;    // shortest half-width of the unit cell
  // distance beyond which the real-space terms are negligible (direct sum: the kernel itself)
  double real_cut() const { return direct ? 3.9 : kRealCut * smin; }
  // images |n_d| <= images(d, r) along axis d reach every term within real_cut() of a point
  // at |r_d| <= rmax (and always the first shell)
  int images(int d, double rmax) const
  {
    return std::max(1, (int) std::floor((real_cut() + rmax) / period[d]));
  }
  // reciprocal vectors k_d = pi m_d / shape[d] with |k| <= pi kmax: |m_d| <= kmax shape[d]
  int kmax_axis(int d) const { return (int) std::floor(kmax * shape[d] + 1e-12); }
  bool k_inside(const int m[3]) const
  {
    double s = 0;
    for (int d = 0; d < 3; ++d) s += (m[d] / shape[d]) * (m[d] / shape[d]);
    return s <= double(kmax) * kmax * (1 + 1e-12);
  }
  double k2_of(const int m[3]) const
  {
    double s = 0;
    for (int d = 0; d < 3; ++d) s += (m[d] / shape[d]) * (m[d] / shape[d]);
    return kPi * kPi * s;
  }
  // reciprocal weight of |k|^2 = k2 (k = 0: Laplace omitted)
  double weight_k2(double k2) const
  {
    if (direct) return 0.0;
    if (!yukawa) return k2 == 0.0 ? 0.0 : (4 * kPi / volume) * std::exp(-k2 / (4 * alpha * alpha)) / k2;
    const double q2 = k2 + kappa * kappa;
    return (4 * kPi / volume) * std::exp(-q2 / (4 * alpha * alpha)) / q2;
  }
  double bare(double r) const { return yukawa ? std::exp(-kappa * r) / r : 1.0 / r; }
  // real-space term phi(r) and F = phi'(r)/r; reg = phi minus the bare kernel
  void real(double r, bool reg, double &v, double &F) const
  {
    if (direct) {    // only used with reg = false
      const double e = std::exp(-kappa * r);
      v = e / r;
      F = -e * (1 + kappa * r) / (r * r * r);
      return;
    }
    if (!yukawa) {
      laplace_real(alpha, r, reg, v, F);
      return;
    }
    const double ar = alpha * r;
    const double gauss = (2 * alpha / kSqrtPi) * std::exp(-ar * ar - a * a);
    const double A = std::exp(kappa * r) * std::erfc(ar + a);
    if (reg) {
      const double C = std::exp(-kappa * r) * std::erfc(a - ar);
      v = (A - C) / (2 * r);
      F = ((kappa * (A + C) - 2 * gauss) / (2 * r) - (A - C) / (2 * r * r)) / r;
    } else {
      const double B = std::exp(-kappa * r) * std::erfc(ar - a);
      v = (A + B) / (2 * r);
      F = ((kappa * (A - B) - 2 * gauss) / (2 * r) - (A + B) / (2 * r * r)) / r;
    }
  }
  // limit of the regular n = 0 term at r = 0
  double reg0() const
  {
    if (direct) return 0.0;
    if (!yukawa) return -2 * alpha / kSqrtPi;
    return kappa * std::erfc(a) - (2 * alpha / kSqrtPi) * std::exp(-a * a);
  }
  // reciprocal weight of k = pi m (m integer vector), m2 = |m|^2 (unit cube)
  double weight(int m2) const { return weight_k2(kPi * kPi * m2); }
  double background() const { return (yukawa || direct) ? 0.0 : -kPi / (volume * alpha * alpha); }
};

}    // namespace kifmm::ewald
