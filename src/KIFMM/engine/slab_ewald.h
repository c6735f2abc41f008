// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Ewald split of the doubly periodic lattice sum (periodic in x and y, open in z: a slab,
// boundary p p f) of the Laplace kernel, in the form of Parry (1975) and Heyes (1977), for a
// unit cell of half-widths shape[0], shape[1] in x, y (periods 2 shape[d], area A):
//   G_2(r) = sum_n erfc(alpha |r + n|) / |r + n|                             (n in the x-y lattice)
//          + (pi / A) sum_{k != 0} cos(k.rho) / |k| [e^{|k| z} erfc(|k|/2alpha + alpha z)
//                                                  + e^{-|k| z} erfc(|k|/2alpha - alpha z)]
//          - (2 pi / A) [z erf(alpha z) + e^{-alpha^2 z^2} / (alpha sqrt(pi))],
// rho = (x, y), k = pi (m_x / shape[0], m_y / shape[1]). G_2 is harmonic away from the lattice
// points (no background: the k = 0 term is the field of a charged sheet, -2 pi |z| / A far from
// it), so a net charge needs no neutralizing background: its far field is that of a uniformly
// charged plane (internal to periodic_grid.cpp and periodic.cpp).
#pragma once

#include "ewald_split.h"

#include <algorithm>
#include <cmath>

namespace kifmm::ewald {

struct SlabSplit {
  double shape[2] = {1.0, 1.0}, period[2] = {2.0, 2.0}, area = 4.0;
  double alpha = 3.0;
  int kmax = 13;    // |k| <= pi kmax (in units of the shortest half-width's scale, as Split)
  double smin = 1.0;

  explicit SlabSplit(const double *cell_shape = nullptr)
  {
    if (cell_shape)
      for (int d = 0; d < 2; ++d) shape[d] = cell_shape[d];
    area = 1.0;
    for (int d = 0; d < 2; ++d) {
      period[d] = 2.0 * shape[d];
      area *= period[d];
    }
    smin = std::min(shape[0], shape[1]);
    alpha = 3.0 / smin;
    kmax = (int) std::ceil(13.0 / smin - 1e-9);
  }
  double real_cut() const { return kRealCut * smin; }
  int images(int d, double rmax) const { return std::max(1, (int) std::floor((real_cut() + rmax) / period[d])); }
  int kmax_axis(int d) const { return (int) std::floor(kmax * shape[d] + 1e-12); }
  // |k| of the reciprocal vector m (0 when outside the cutoff sphere: skipped)
  double k_of(int mx, int my) const
  {
    const double a = mx / shape[0], b = my / shape[1], s = a * a + b * b;
    return s <= double(kmax) * kmax * (1 + 1e-12) ? kPi * std::sqrt(s) : 0.0;
  }
  // e^{k z} erfc(k / 2 alpha + alpha z) without overflow: for x = k/2alpha + alpha z > 0 it is
  // e^{-k^2/4alpha^2 - alpha^2 z^2} erfcx(x)
  double ez_erfc(double k, double z) const
  {
    const double x = k / (2 * alpha) + alpha * z;
    if (x <= 0) return std::exp(k * z) * std::erfc(x);
    const double e = -(k / (2 * alpha)) * (k / (2 * alpha)) - alpha * alpha * z * z;
    if (e < -745) return 0.0;
    double erfcx;
    if (x < 26) {
      erfcx = std::exp(x * x) * std::erfc(x);
    } else {    // asymptotic series, relative error < 1e-17 here
      const double t = 1 / (2 * x * x);
      erfcx = (1 - t * (1 - 3 * t * (1 - 5 * t))) / (x * kSqrtPi);
    }
    return std::exp(e) * erfcx;
  }
  // d/dz of e^{k z} erfc(k / 2 alpha + alpha z) = k e^{kz} erfc(..) - (2 alpha / sqrt(pi)) e^{kz - x^2}
  double ez_erfc_dz(double k, double z) const
  {
    const double g = (2 * alpha / kSqrtPi) * std::exp(-(k / (2 * alpha)) * (k / (2 * alpha)) - alpha * alpha * z * z);
    return k * ez_erfc(k, z) - g;
  }
  // reciprocal weight of k at height z (value and d/dz): (pi / (A k)) [f(k, z) + f(k, -z)]
  void weight(double k, double z, double &w, double &dw) const
  {
    const double c = kPi / (area * k);
    w = c * (ez_erfc(k, z) + ez_erfc(k, -z));
    dw = c * (ez_erfc_dz(k, z) - ez_erfc_dz(k, -z));
  }
  // d/dk of the reciprocal weight at height z (the first-moment tables of the virial):
  // d/dk e^{kz} erfc(k/2alpha + alpha z) = z e^{kz} erfc(..) - e^{-k^2/4alpha^2 - alpha^2 z^2} / (alpha sqrt(pi))
  double weight_dk(double k, double z) const
  {
    const double c = kPi / (area * k), fp = ez_erfc(k, z), fm = ez_erfc(k, -z);
    const double g = std::exp(-(k / (2 * alpha)) * (k / (2 * alpha)) - alpha * alpha * z * z) / (alpha * kSqrtPi);
    return -c * (fp + fm) / k + c * (z * (fp - fm) - 2 * g);
  }
  // the k = 0 term and its d/dz
  void zero_term(double z, double &v, double &dv) const
  {
    v = -(2 * kPi / area) * (z * std::erf(alpha * z) + std::exp(-alpha * alpha * z * z) / (alpha * kSqrtPi));
    dv = -(2 * kPi / area) * std::erf(alpha * z);
  }
  // real-space term (Laplace) phi(r) and F = phi'(r) / r; reg = phi minus the bare 1/r
  void real(double r, bool reg, double &v, double &F) const { laplace_real(alpha, r, reg, v, F); }
  double reg0() const { return -2 * alpha / kSqrtPi; }
};

}    // namespace kifmm::ewald
