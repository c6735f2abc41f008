// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Near-field particle-to-particle kernel loop (templated on the kernel so the pair function
// inlines). Structure of arrays; for each target, the loop over sources is an OpenMP SIMD
// reduction (vectorized, deterministic for a given build). Pairs with r2 == 0 are masked:
// they contribute nothing and no inf/NaN is formed (r2 is replaced by 1 before 1/sqrt).
// Results are ADDED to pot / gx,gy,gz. Also used with surface points as sources or targets
// (P2M, P2L, M2P, L2P).
#pragma once

#include "kernels.h"
#include "p2p_dipole.h"
#include "point_spans.h"

#include <cmath>
#include <cstddef>
#include <type_traits>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace kifmm {

#if defined(__AVX512F__)
// Laplace with AVX-512: 1/sqrt from vrsqrt14pd (14 bits) refined by one 4th-order step
// (relative error ~1e-16, full double accuracy), 8 sources per step, masked tail and r = 0.
template <bool POT, bool GRAD, bool COUNT>
inline void p2p_laplace_avx512(const PointSpan &t, const PointSpan &s, const ResultSpan &r, std::size_t *n_zero)
{
  const std::size_t nt = t.n, ns = s.n;
  const double *__restrict tx = t.x, *__restrict ty = t.y, *__restrict tz = t.z;
  const double *__restrict sx = s.x, *__restrict sy = s.y, *__restrict sz = s.z, *__restrict sq = s.q;
  double *__restrict pot = r.pot, *__restrict gx = r.gx, *__restrict gy = r.gy, *__restrict gz = r.gz;
  const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0), c1 = _mm512_set1_pd(0.5),
                c2 = _mm512_set1_pd(0.375), c3 = _mm512_set1_pd(0.3125);
  std::size_t zeros = 0;
  const std::size_t nfull = ns & ~std::size_t(7);
  const __mmask8 tail = (__mmask8) ((1u << (ns - nfull)) - 1u);
  for (std::size_t i = 0; i < nt; ++i) {
    const __m512d xi = _mm512_set1_pd(tx[i]), yi = _mm512_set1_pd(ty[i]), zi = _mm512_set1_pd(tz[i]);
    __m512d ap = zero, ax = zero, ay = zero, az = zero;
    auto step = [&](__m512d sxj, __m512d syj, __m512d szj, __m512d qj, __mmask8 valid) {
      const __m512d dx = _mm512_sub_pd(xi, sxj), dy = _mm512_sub_pd(yi, syj), dz = _mm512_sub_pd(zi, szj);
      const __m512d r2 = _mm512_fmadd_pd(dz, dz, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dx, dx)));
      const __mmask8 ok = _mm512_mask_cmp_pd_mask(valid, r2, zero, _CMP_GT_OQ);
      if constexpr (COUNT) zeros += (std::size_t) __builtin_popcount((unsigned) (valid & ~ok));
      // masked lanes (r = 0 or past the end) may hold inf/NaN until the final masked
      // multiply sets y = 0 there
      // y0 = rsqrt14(r2) (|e| < 2^-14 with e = 1 - r2 y0^2), then one 4th-order correction
      // y = y0 (1 + e/2 + 3e^2/8 + 5e^3/16): residual ~0.27 e^4 < 4e-18, full double accuracy
      const __m512d y0 = _mm512_rsqrt14_pd(r2);
      const __m512d e = _mm512_fnmadd_pd(r2, _mm512_mul_pd(y0, y0), one);
      const __m512d c = _mm512_fmadd_pd(e, _mm512_fmadd_pd(e, c3, c2), c1);
      const __m512d y = _mm512_maskz_mov_pd(ok, _mm512_fmadd_pd(_mm512_mul_pd(y0, e), c, y0));
      const __m512d qinvr = _mm512_mul_pd(qj, y);    // q/r, 0 where masked
      if constexpr (POT) ap = _mm512_add_pd(ap, qinvr);
      if constexpr (GRAD) {
        const __m512d f = _mm512_mul_pd(qinvr, _mm512_mul_pd(y, y));    // q/r^3
        ax = _mm512_fnmadd_pd(f, dx, ax);
        ay = _mm512_fnmadd_pd(f, dy, ay);
        az = _mm512_fnmadd_pd(f, dz, az);
      }
    };
    for (std::size_t j = 0; j < nfull; j += 8)
      step(_mm512_loadu_pd(sx + j), _mm512_loadu_pd(sy + j), _mm512_loadu_pd(sz + j), _mm512_loadu_pd(sq + j),
           (__mmask8) 0xff);
    if (tail)
      step(_mm512_maskz_loadu_pd(tail, sx + nfull), _mm512_maskz_loadu_pd(tail, sy + nfull),
           _mm512_maskz_loadu_pd(tail, sz + nfull), _mm512_maskz_loadu_pd(tail, sq + nfull), tail);
    if constexpr (POT) pot[i] += _mm512_reduce_add_pd(ap);
    if constexpr (GRAD) {
      gx[i] += _mm512_reduce_add_pd(ax);
      gy[i] += _mm512_reduce_add_pd(ay);
      gz[i] += _mm512_reduce_add_pd(az);
    }
  }
  if constexpr (COUNT) {
    if (n_zero) *n_zero += zeros;
  }
}
#endif

// Targets t, sources s (with strengths), results added to r; n_zero (COUNT) counts the pairs
// at r = 0.
template <class K, bool POT, bool GRAD, bool COUNT>
inline void p2p(const K &k, const PointSpan &t, const PointSpan &s, const ResultSpan &r,
                std::size_t *n_zero = nullptr)
{
  if (s.mx || r.hxx) {    // dipole sources or field gradients at the targets (p2p_dipole.h)
    p2p_dipole<K, POT, GRAD, COUNT>(k, t, s, r, n_zero);
    return;
  }
#if defined(__AVX512F__)
  if constexpr (std::is_same_v<K, LaplaceKernel>) {
    p2p_laplace_avx512<POT, GRAD, COUNT>(t, s, r, n_zero);
    return;
  }
#endif
  const std::size_t nt = t.n, ns = s.n;
  const double *__restrict tx = t.x, *__restrict ty = t.y, *__restrict tz = t.z;
  const double *__restrict sx = s.x, *__restrict sy = s.y, *__restrict sz = s.z, *__restrict sq = s.q;
  double *__restrict pot = r.pot, *__restrict gx = r.gx, *__restrict gy = r.gy, *__restrict gz = r.gz;
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

// Runtime dispatch on whether the potential is wanted (the gradient always is).
template <class K, bool COUNT>
inline void p2p_pg(const K &k, bool want_pot, const PointSpan &t, const PointSpan &s, const ResultSpan &r,
                   std::size_t *n_zero = nullptr)
{
  if (want_pot) p2p<K, true, true, COUNT>(k, t, s, r, n_zero);
  else p2p<K, false, true, COUNT>(k, t, s, r, n_zero);
}

}    // namespace kifmm
