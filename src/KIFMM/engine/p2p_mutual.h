// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Mutual (Newton's third law) near-field kernel: one pass over the pairs of two point sets that
// are both sources and targets gives the potential and gradient on both sides. Used by the
// periodic near field when sources and targets are the same points (periodic_core.h): each
// pair of adjacent leaves (with its image shift) is evaluated once instead of twice.
//
// Set A and set B (MutualSpan: points with strengths, and their accumulators), B displaced by
// sh: with d = x_a - (x_b + sh), A gets q_b G, q_b F d and B gets q_a G, -q_a F d (F = G'(r)/r, the
// convention of kernels.h). `self`: A and B are the same leaf (sh = 0), only pairs j > i.
// Pairs with r2 == 0 are masked as in p2p.h; n_zero counts them as ordered pairs (both
// directions; in `self` mode a point with itself counts once, as the one-sided loop does).
// Results are ADDED.
#pragma once

#include "kernels.h"
#include "p2p.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace kifmm {

// One side of a mutual near-field call: points with strengths, and their accumulators.
struct MutualSpan {
  PointSpan pts;
  ResultSpan acc;
};

#if defined(__AVX512F__)
// One step of 8 B points against NI A targets (NI = 1 or 2): the B points and B accumulators
// are loaded and stored once for all NI targets. B arrays are the padded aligned copies of
// p2p_mutual_laplace_avx512 (full vectors, no masks; padding has q = 0 and lies far away).
template <bool POT, int NI>
inline void mutual_step(const __m512d *xi, const __m512d *yi, const __m512d *zi, const __m512d *qi, __m512d *acp,
                        __m512d *acx, __m512d *acy, __m512d *acz, const double *bx, const double *by,
                        const double *bz, const double *bq, double *bp, double *bgx, double *bgy, double *bgz,
                        std::size_t &zeros)
{
  const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0), c1 = _mm512_set1_pd(0.5),
                c2 = _mm512_set1_pd(0.375), c3 = _mm512_set1_pd(0.3125);
  const __m512d sxj = _mm512_load_pd(bx), syj = _mm512_load_pd(by), szj = _mm512_load_pd(bz), qj = _mm512_load_pd(bq);
  __m512d pb = POT ? _mm512_load_pd(bp) : zero, gbx = _mm512_load_pd(bgx), gby = _mm512_load_pd(bgy),
          gbz = _mm512_load_pd(bgz);
  for (int t = 0; t < NI; ++t) {
    const __m512d dx = _mm512_sub_pd(xi[t], sxj), dy = _mm512_sub_pd(yi[t], syj), dz = _mm512_sub_pd(zi[t], szj);
    const __m512d r2 = _mm512_fmadd_pd(dz, dz, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dx, dx)));
    const __mmask8 ok = _mm512_cmp_pd_mask(r2, zero, _CMP_GT_OQ);
    zeros += (std::size_t) __builtin_popcount((unsigned) (__mmask8) ~ok);
    // 1/sqrt as in p2p.h: rsqrt14 and one 4th-order correction (full double accuracy)
    const __m512d y0 = _mm512_rsqrt14_pd(r2);
    const __m512d e = _mm512_fnmadd_pd(r2, _mm512_mul_pd(y0, y0), one);
    const __m512d c = _mm512_fmadd_pd(e, _mm512_fmadd_pd(e, c3, c2), c1);
    const __m512d y = _mm512_maskz_mov_pd(ok, _mm512_fmadd_pd(_mm512_mul_pd(y0, e), c, y0));
    const __m512d y3 = _mm512_mul_pd(y, _mm512_mul_pd(y, y));    // 1/r^3, 0 where masked
    const __m512d fa = _mm512_mul_pd(qj, y3), fb = _mm512_mul_pd(qi[t], y3);
    if constexpr (POT) {
      acp[t] = _mm512_fmadd_pd(qj, y, acp[t]);
      pb = _mm512_fmadd_pd(qi[t], y, pb);
    }
    acx[t] = _mm512_fnmadd_pd(fa, dx, acx[t]);    // A: -q_j d / r^3
    acy[t] = _mm512_fnmadd_pd(fa, dy, acy[t]);
    acz[t] = _mm512_fnmadd_pd(fa, dz, acz[t]);
    gbx = _mm512_fmadd_pd(fb, dx, gbx);           // B: +q_i d / r^3
    gby = _mm512_fmadd_pd(fb, dy, gby);
    gbz = _mm512_fmadd_pd(fb, dz, gbz);
  }
  if constexpr (POT) _mm512_store_pd(bp, pb);
  _mm512_store_pd(bgx, gbx);
  _mm512_store_pd(bgy, gby);
  _mm512_store_pd(bgz, gbz);
}

// Cross pairs of two different leaves (not `self`, see p2p_mutual), B at nsh displacements
// sh[3 s .. 3 s + 2] (the same cell met at several image shifts: one pass over all its copies).
template <bool POT>
inline void p2p_mutual_laplace_avx512(const MutualSpan &A, const MutualSpan &B, const double *sh, int nsh,
                                      std::size_t *n_zero)
{
  const std::size_t na = A.pts.n, nb1 = B.pts.n, nb = nb1 * nsh;
  const double *ax = A.pts.x, *ay = A.pts.y, *az = A.pts.z, *aq = A.pts.q;
  double *ap = A.acc.pot, *agx = A.acc.gx, *agy = A.acc.gy, *agz = A.acc.gz;
  const double *bx = B.pts.x, *by = B.pts.y, *bz = B.pts.z, *bq = B.pts.q;
  double *bp = B.acc.pot, *bgx = B.acc.gx, *bgy = B.acc.gy, *bgz = B.acc.gz;
  // aligned, padded copies of B (thread-local scratch, reused): x y z q | pot gx gy gz
  thread_local std::vector<double> buf;
  const std::size_t nbp = (nb + 7) & ~std::size_t(7);
  if (buf.size() < 8 * nbp + 8) buf.resize(8 * nbp + 8);
  double *base = buf.data();
  while (reinterpret_cast<std::uintptr_t>(base) % 64 != 0) ++base;
  double *cx = base, *cy = cx + nbp, *cz = cy + nbp, *cq = cz + nbp, *cp = cq + nbp, *cgx = cp + nbp,
         *cgy = cgx + nbp, *cgz = cgy + nbp;
  for (int s = 0; s < nsh; ++s)
    for (std::size_t jb = 0, j = s * nb1; jb < nb1; ++jb, ++j) {
      cx[j] = bx[jb] + sh[3 * s];
      cy[j] = by[jb] + sh[3 * s + 1];
      cz[j] = bz[jb] + sh[3 * s + 2];
      cq[j] = bq[jb];
    }
  for (std::size_t j = nb; j < nbp; ++j) {    // padding: far away, q = 0
    cx[j] = cy[j] = cz[j] = 1e100;
    cq[j] = 0.0;
  }
  std::fill(cp, cp + 4 * nbp, 0.0);    // pot gx gy gz
  const __m512d zero = _mm512_setzero_pd();
  std::size_t zeros = 0;
  std::size_t i = 0;
  for (; i + 2 <= na; i += 2) {
    __m512d xi[2] = {_mm512_set1_pd(ax[i]), _mm512_set1_pd(ax[i + 1])},
            yi[2] = {_mm512_set1_pd(ay[i]), _mm512_set1_pd(ay[i + 1])},
            zi[2] = {_mm512_set1_pd(az[i]), _mm512_set1_pd(az[i + 1])},
            qi[2] = {_mm512_set1_pd(aq[i]), _mm512_set1_pd(aq[i + 1])};
    __m512d acp[2] = {zero, zero}, acx[2] = {zero, zero}, acy[2] = {zero, zero}, acz[2] = {zero, zero};
    for (std::size_t j = 0; j < nbp; j += 8)
      mutual_step<POT, 2>(xi, yi, zi, qi, acp, acx, acy, acz, cx + j, cy + j, cz + j, cq + j, cp + j, cgx + j,
                          cgy + j, cgz + j, zeros);
    for (int t = 0; t < 2; ++t) {
      if constexpr (POT) ap[i + t] += _mm512_reduce_add_pd(acp[t]);
      agx[i + t] += _mm512_reduce_add_pd(acx[t]);
      agy[i + t] += _mm512_reduce_add_pd(acy[t]);
      agz[i + t] += _mm512_reduce_add_pd(acz[t]);
    }
  }
  if (i < na) {
    __m512d xi[1] = {_mm512_set1_pd(ax[i])}, yi[1] = {_mm512_set1_pd(ay[i])}, zi[1] = {_mm512_set1_pd(az[i])},
            qi[1] = {_mm512_set1_pd(aq[i])};
    __m512d acp[1] = {zero}, acx[1] = {zero}, acy[1] = {zero}, acz[1] = {zero};
    for (std::size_t j = 0; j < nbp; j += 8)
      mutual_step<POT, 1>(xi, yi, zi, qi, acp, acx, acy, acz, cx + j, cy + j, cz + j, cq + j, cp + j, cgx + j,
                          cgy + j, cgz + j, zeros);
    if constexpr (POT) ap[i] += _mm512_reduce_add_pd(acp[0]);
    agx[i] += _mm512_reduce_add_pd(acx[0]);
    agy[i] += _mm512_reduce_add_pd(acy[0]);
    agz[i] += _mm512_reduce_add_pd(acz[0]);
  }
  for (int s = 0; s < nsh; ++s)
    for (std::size_t jb = 0, j = s * nb1; jb < nb1; ++jb, ++j) {
      if constexpr (POT) bp[jb] += cp[j];
      bgx[jb] += cgx[j];
      bgy[jb] += cgy[j];
      bgz[jb] += cgz[j];
    }
  if (n_zero) *n_zero += 2 * zeros;
}
#endif

template <class K, bool POT>
inline void p2p_mutual(const K &k, bool self, const MutualSpan &A, const MutualSpan &B, const double sh[3],
                       std::size_t *n_zero)
{
  if (A.pts.mx || A.acc.hxx) {    // dipoles or second derivatives (p2p_dipole.h)
    p2p_dipole_mutual<K, POT>(k, self, A.pts, A.acc, B.pts, B.acc, sh, n_zero);
    return;
  }
#if defined(__AVX512F__)
  if constexpr (std::is_same_v<K, LaplaceKernel>) {
    if (self) {    // the leaf with itself: the one-sided loop over all pairs costs the same
      p2p<K, POT, true, true>(k, A.pts, B.pts, A.acc, n_zero);
      return;
    }
    p2p_mutual_laplace_avx512<POT>(A, B, sh, 1, n_zero);
    return;
  }
#endif
  const std::size_t na = A.pts.n, nb = B.pts.n;
  const double *__restrict ax = A.pts.x, *__restrict ay = A.pts.y, *__restrict az = A.pts.z, *__restrict aq = A.pts.q;
  double *ap = A.acc.pot, *agx = A.acc.gx, *agy = A.acc.gy, *agz = A.acc.gz;
  const double *__restrict bx = B.pts.x, *__restrict by = B.pts.y, *__restrict bz = B.pts.z, *__restrict bq = B.pts.q;
  double *bp = B.acc.pot, *bgx = B.acc.gx, *bgy = B.acc.gy, *bgz = B.acc.gz;
  std::size_t zeros = 0;
  for (std::size_t i = 0; i < na; ++i) {
    const double xi = ax[i] - sh[0], yi = ay[i] - sh[1], zi = az[i] - sh[2], qi = aq[i];
    double p = 0, gx = 0, gy = 0, gz = 0;
    long nz = 0;
    const std::size_t j0 = self ? i + 1 : 0;
    // B's accumulators are distinct from A's (self: j > i never meets index i)
    double *__restrict pb = bp, *__restrict gxb = bgx, *__restrict gyb = bgy, *__restrict gzb = bgz;
#pragma omp simd reduction(+ : p, gx, gy, gz, nz)
    for (std::size_t j = j0; j < nb; ++j) {
      const double dx = xi - bx[j], dy = yi - by[j], dz = zi - bz[j];
      const double r2 = dx * dx + dy * dy + dz * dz;
      const bool ok = r2 > 0.0;
      const double r2s = ok ? r2 : 1.0;
      const double invr = 1.0 / std::sqrt(r2s);
      double G, F;
      k.value_grad(r2s, invr, G, F);
      G = ok ? G : 0.0;
      F = ok ? F : 0.0;
      if constexpr (POT) {
        p += bq[j] * G;
        pb[j] += qi * G;
      }
      gx += bq[j] * F * dx;
      gy += bq[j] * F * dy;
      gz += bq[j] * F * dz;
      gxb[j] -= qi * F * dx;
      gyb[j] -= qi * F * dy;
      gzb[j] -= qi * F * dz;
      nz += ok ? 0 : 1;
    }
    if constexpr (POT) ap[i] += p;
    agx[i] += gx;
    agy[i] += gy;
    agz[i] += gz;
    zeros += (std::size_t) nz;
  }
  if (n_zero) *n_zero += 2 * zeros + (self ? na : 0);
}

// Two different leaves, B at nsh displacements sh[3 s .. 3 s + 2] (one cell met at several image
// shifts of a thin periodic side): as nsh calls of p2p_mutual, in one pass where the kernel
// allows it.
template <class K, bool POT>
inline void p2p_mutual_shifts(const K &k, const MutualSpan &A, const MutualSpan &B, const double *sh, int nsh,
                              std::size_t *n_zero)
{
#if defined(__AVX512F__)
  if constexpr (std::is_same_v<K, LaplaceKernel>) {
    if (!A.pts.mx && !A.acc.hxx) {
      p2p_mutual_laplace_avx512<POT>(A, B, sh, nsh, n_zero);
      return;
    }
  }
#endif
  for (int s = 0; s < nsh; ++s) p2p_mutual<K, POT>(k, false, A, B, sh + 3 * s, n_zero);
}

}    // namespace kifmm
