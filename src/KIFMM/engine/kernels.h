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
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace kifmm {

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
  std::string id() const { return "laplace"; }
};

// Yukawa (modified Helmholtz) G = exp(-kappa r)/r.
struct YukawaKernel {
  double kappa = 0.0;
  double value(double r2, double invr) const { return std::exp(-kappa * r2 * invr) * invr; }
  void value_grad(double r2, double invr, double &G, double &F) const
  {
    const double r = r2 * invr;
    G = std::exp(-kappa * r) * invr;
    F = -G * (1.0 + kappa * r) * invr * invr;
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
