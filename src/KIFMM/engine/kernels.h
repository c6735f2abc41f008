// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Kernel types of the engine. A kernel is a small value type with its pair evaluation:
//
//   double value(double r2, double invr) const;                      G(r)
//   void value_grad(double r2, double invr, double &G, double &F) const;  G(r), F = G'(r)/r
//
// called only with r2 > 0 and invr = 1/sqrt(r2) (the engine masks r = 0 itself). The
// gradient of G(|x-y|) with respect to the target x is F * (x - y). Everything else
// (surfaces, operators, M2L FFTs) is derived numerically from value().
//
// Optional members that let the engine reuse operators across levels (see kernel_scaling.h):
//   static constexpr bool homogeneous = true; static constexpr double degree = d;
//        G(s r) = s^d G(r): one operator set at unit box size, scaled per level.
//   K rescaled(double h, double &s) const;   G_K(h u) = s * G_{K'}(u): operators of a box of
//        half-width h are those of K' at unit half-width (cache key = K'.id()).
//   std::string id() const;                  unique name for the operator caches.
// A kernel with none of these gets per-level operators computed at the physical box size.
//
// Optional, for dipole sources and field gradients at targets (evaluate_dipoles):
//   void derivs3(double r2, double invr, double &G, double &F, double &H, double &T) const;
//        G, F = G'/r, H = F'/r, T = H'/r: the derivatives of G(|d|) in d up to the third are
//        dG = F d, ddG = F I + H d d, dddG_abc = H (d_a I_bc + d_b I_ac + d_c I_ab) + T d_a d_b d_c.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace kifmm {

// exp(x) written so that the compiler vectorizes it inside the P2P loops (glibc offers its
// vector exp only under -ffast-math). Cody-Waite reduction x = k ln2 + r, |r| <= ln2/2, Taylor
// polynomial of degree 13 (truncation < 5e-18), scaling by 2^k through the exponent bits.
// Accurate to a few ulp for x in [-708, 709]; returns 0 below -708 (the kernels only need
// x <= 0).
inline double exp_accurate(double x)
{
  constexpr double kLog2e = 1.4426950408889634, kLn2Hi = 6.93147180369123816490e-01,
                   kLn2Lo = 1.90821492927058770002e-10;
  const double xc = x < -708.0 ? -708.0 : (x > 709.0 ? 709.0 : x);
  const double k = __builtin_nearbyint(xc * kLog2e);
  const double r = (xc - k * kLn2Hi) - k * kLn2Lo;
  double p = 1.0 / 6227020800.0;    // 1/13!
  p = p * r + 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  const long long bits = ((long long) k + 1023) << 52;
  double scale;
  __builtin_memcpy(&scale, &bits, sizeof scale);
  const double v = p * scale;
  return x < -708.0 ? 0.0 : v;
}

// Laplace G = 1/r (no 4 pi).
struct LaplaceKernel {
  static constexpr bool homogeneous = true;
  static constexpr double degree = -1.0;
  double value(double, double invr) const { return invr; }
  void value_grad(double, double invr, double &G, double &F) const
  {
    G = invr;
    F = -invr * invr * invr;
  }
  void derivs3(double, double invr, double &G, double &F, double &H, double &T) const
  {
    const double i2 = invr * invr;
    G = invr;
    F = -G * i2;
    H = -3.0 * F * i2;
    T = -5.0 * H * i2;
  }
  std::string id() const { return "laplace"; }
};

// Yukawa (modified Helmholtz) G = exp(-kappa r)/r.
struct YukawaKernel {
  double kappa = 0.0;
  double value(double r2, double invr) const { return exp_accurate(-kappa * r2 * invr) * invr; }
  void value_grad(double r2, double invr, double &G, double &F) const
  {
    const double r = r2 * invr;
    G = exp_accurate(-kappa * r) * invr;
    F = -G * (1.0 + kappa * r) * invr * invr;
  }
  void derivs3(double r2, double invr, double &G, double &F, double &H, double &T) const
  {
    const double kr = kappa * r2 * invr, i2 = invr * invr;
    G = exp_accurate(-kr) * invr;
    F = -G * (1.0 + kr) * i2;
    H = G * (3.0 + kr * (3.0 + kr)) * i2 * i2;
    T = -G * (15.0 + kr * (15.0 + kr * (6.0 + kr))) * i2 * i2 * i2;
  }
  // G_kappa(h u) = (1/h) G_{kappa h}(u)
  YukawaKernel rescaled(double h, double &s) const
  {
    s = 1.0 / h;
    return YukawaKernel{kappa * h};
  }
  std::string id() const
  {
    char buf[64];
    std::snprintf(buf, sizeof buf, "yukawa_%a", kappa);
    return buf;
  }
};

}    // namespace kifmm
