// Near-field particle-to-particle kernel loop (templated on the kernel so the pair function
// inlines). Structure of arrays; for each target, the loop over sources is an OpenMP SIMD
// reduction (vectorized, deterministic for a given build). Pairs with r2 == 0 are masked:
// they contribute nothing and no inf/NaN is formed (r2 is replaced by 1 before 1/sqrt).
// Results are ADDED to pot / gx,gy,gz. Also used with surface points as sources or targets
// (P2M, P2L, M2P, L2P).
#pragma once

#include <cmath>
#include <cstddef>

namespace kifmm {

template <class K, bool POT, bool GRAD, bool COUNT>
inline void p2p(const K &k, std::size_t nt, const double *__restrict tx, const double *__restrict ty,
                const double *__restrict tz, std::size_t ns, const double *__restrict sx,
                const double *__restrict sy, const double *__restrict sz, const double *__restrict sq,
                double *__restrict pot, double *__restrict gx, double *__restrict gy,
                double *__restrict gz, std::size_t *n_zero = nullptr)
{
  std::size_t zeros = 0;
  for (std::size_t i = 0; i < nt; ++i) {
    const double xi = tx[i], yi = ty[i], zi = tz[i];
    double p = 0, ax = 0, ay = 0, az = 0;
    long nz = 0;
#pragma omp simd reduction(+ : p, ax, ay, az, nz)
    for (std::size_t j = 0; j < ns; ++j) {
      const double dx = xi - sx[j], dy = yi - sy[j], dz = zi - sz[j];
      const double r2 = dx * dx + dy * dy + dz * dz;
      const bool ok = r2 > 0.0;
      const double r2s = ok ? r2 : 1.0;
      const double invr = 1.0 / std::sqrt(r2s);
      if constexpr (GRAD) {
        double G, F;
        k.value_grad(r2s, invr, G, F);
        const double qF = ok ? sq[j] * F : 0.0;
        if constexpr (POT) p += ok ? sq[j] * G : 0.0;
        ax += qF * dx;
        ay += qF * dy;
        az += qF * dz;
      } else {
        const double G = k.value(r2s, invr);
        p += ok ? sq[j] * G : 0.0;
      }
      if constexpr (COUNT) nz += ok ? 0 : 1;
    }
    if constexpr (POT) pot[i] += p;
    if constexpr (GRAD) {
      gx[i] += ax;
      gy[i] += ay;
      gz[i] += az;
    }
    zeros += (std::size_t) nz;
  }
  if constexpr (COUNT) {
    if (n_zero) *n_zero += zeros;
  }
}

// Runtime dispatch on whether the potential is wanted.
template <class K, bool COUNT>
inline void p2p_pg(const K &k, bool want_pot, std::size_t nt, const double *tx, const double *ty,
                   const double *tz, std::size_t ns, const double *sx, const double *sy, const double *sz,
                   const double *sq, double *pot, double *gx, double *gy, double *gz,
                   std::size_t *n_zero = nullptr)
{
  if (want_pot) p2p<K, true, true, COUNT>(k, nt, tx, ty, tz, ns, sx, sy, sz, sq, pot, gx, gy, gz, n_zero);
  else p2p<K, false, true, COUNT>(k, nt, tx, ty, tz, ns, sx, sy, sz, sq, pot, gx, gy, gz, n_zero);
}

}    // namespace kifmm
