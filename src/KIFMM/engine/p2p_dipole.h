// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Near-field loop with point dipoles: sources carry a charge q and a dipole moment m (either
// may be absent), targets may take the second derivatives of the potential besides its value
// and gradient. With d = x - y (target x, source y) and the kernel's derivatives (kernels.h,
// derivs3: G, F = G'/r, H = F'/r, T = H'/r), one source contributes
//   phi    = q G - F (m.d)                                   (m . grad_y G)
//   g_a    = q F d_a - H (m.d) d_a - F m_a                      (d phi / d x_a)
//   h_ab   = q (F I_ab + H d_a d_b)
//            - T (m.d) d_a d_b - H ((m.d) I_ab + d_a m_b + m_a d_b)   (d g_a / d x_b)
// Used by p2p() when a span has dipoles or second derivatives (the charge-only loops stay as
// they are). Pairs at r = 0 are masked as in p2p.h.
#pragma once

#include "point_spans.h"

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <type_traits>

namespace kifmm {

template <class K, class = void> struct has_derivs3 : std::false_type {};
template <class K>
struct has_derivs3<K, std::void_t<decltype(std::declval<const K &>().derivs3(1.0, 1.0, std::declval<double &>(),
                                                                            std::declval<double &>(),
                                                                            std::declval<double &>(),
                                                                            std::declval<double &>()))>>
    : std::true_type {};

template <class K, bool POT, bool GRAD, bool DIP, bool HESS, bool COUNT>
inline void p2p_dipole_loop(const K &k, const PointSpan &t, const PointSpan &s, const ResultSpan &r,
                            std::size_t *n_zero)
{
  const std::size_t nt = t.n, ns = s.n;
  const double *__restrict tx = t.x, *__restrict ty = t.y, *__restrict tz = t.z;
  const double *__restrict sx = s.x, *__restrict sy = s.y, *__restrict sz = s.z, *__restrict sq = s.q;
  const double *__restrict mx = s.mx, *__restrict my = s.my, *__restrict mz = s.mz;
  std::size_t zeros = 0;
  for (std::size_t i = 0; i < nt; ++i) {
    const double xi = tx[i], yi = ty[i], zi = tz[i];
    double p = 0, ax = 0, ay = 0, az = 0, hxx = 0, hyy = 0, hzz = 0, hxy = 0, hxz = 0, hyz = 0;
    long nz = 0;
#pragma omp simd reduction(+ : p, ax, ay, az, hxx, hyy, hzz, hxy, hxz, hyz, nz)
    for (std::size_t j = 0; j < ns; ++j) {
      const double dx = xi - sx[j], dy = yi - sy[j], dz = zi - sz[j];
      const double r2 = dx * dx + dy * dy + dz * dz;
      const bool ok = r2 > 0.0;
      const double r2s = ok ? r2 : 1.0;
      const double invr = 1.0 / std::sqrt(r2s);
      double G, F, H, T;
      k.derivs3(r2s, invr, G, F, H, T);
      const double q = ok ? (sq ? sq[j] : 0.0) : 0.0;
      double md = 0, ux = 0, uy = 0, uz = 0;
      if constexpr (DIP) {
        ux = ok ? mx[j] : 0.0;
        uy = ok ? my[j] : 0.0;
        uz = ok ? mz[j] : 0.0;
        md = ux * dx + uy * dy + uz * dz;
      }
      if constexpr (POT) p += q * G - F * md;
      if constexpr (GRAD) {
        const double c = q * F - H * md;
        ax += c * dx - F * ux;
        ay += c * dy - F * uy;
        az += c * dz - F * uz;
      }
      if constexpr (HESS) {
        const double diag = q * F - H * md, dd = q * H - T * md;
        hxx += diag + dd * dx * dx - 2.0 * H * dx * ux;
        hyy += diag + dd * dy * dy - 2.0 * H * dy * uy;
        hzz += diag + dd * dz * dz - 2.0 * H * dz * uz;
        hxy += dd * dx * dy - H * (dx * uy + ux * dy);
        hxz += dd * dx * dz - H * (dx * uz + ux * dz);
        hyz += dd * dy * dz - H * (dy * uz + uy * dz);
      }
      if constexpr (COUNT) nz += ok ? 0 : 1;
    }
    if constexpr (POT) r.pot[i] += p;
    if constexpr (GRAD) {
      r.gx[i] += ax;
      r.gy[i] += ay;
      r.gz[i] += az;
    }
    if constexpr (HESS) {
      r.hxx[i] += hxx;
      r.hyy[i] += hyy;
      r.hzz[i] += hzz;
      r.hxy[i] += hxy;
      r.hxz[i] += hxz;
      r.hyz[i] += hyz;
    }
    zeros += (std::size_t) nz;
  }
  if constexpr (COUNT) {
    if (n_zero) *n_zero += zeros;
  }
}

// Targets t, sources s (charges and/or dipoles), results added to r (second derivatives when
// r.hxx is not null; they need GRAD).
template <class K, bool POT, bool GRAD, bool COUNT>
inline void p2p_dipole(const K &k, const PointSpan &t, const PointSpan &s, const ResultSpan &r, std::size_t *n_zero)
{
  if constexpr (!has_derivs3<K>::value) {
    (void) k, (void) t, (void) s, (void) r, (void) n_zero;
    throw std::invalid_argument("kifmm: this kernel has no third derivatives (derivs3): no dipoles");
  } else {
    const bool dip = s.mx != nullptr, hess = GRAD && r.hxx != nullptr;
    if (dip && hess) p2p_dipole_loop<K, POT, GRAD, true, true, COUNT>(k, t, s, r, n_zero);
    else if (dip) p2p_dipole_loop<K, POT, GRAD, true, false, COUNT>(k, t, s, r, n_zero);
    else if (hess) p2p_dipole_loop<K, POT, GRAD, false, true, COUNT>(k, t, s, r, n_zero);
    else p2p_dipole_loop<K, POT, GRAD, false, false, COUNT>(k, t, s, r, n_zero);
  }
}

// Mutual form (Newton's third law) for two sets A, B that are both sources and targets, B
// displaced by sh: with d = x_a - (x_b + sh), A gets the terms above with (q_b, m_b, d) and B
// those with (q_a, m_a, -d): the odd terms change sign. self: A and B are the same set, pairs
// j > i only. n_zero as p2p_mutual (p2p_mutual.h). Both spans carry second derivatives or
// neither; dipoles likewise.
template <class K, bool POT, bool DIP, bool HESS>
inline void p2p_dipole_mutual_loop(const K &k, bool self, const PointSpan &A, const ResultSpan &RA,
                                   const PointSpan &B, const ResultSpan &RB, const double sh[3], std::size_t *n_zero)
{
  const std::size_t na = A.n, nb = B.n;
  const double *__restrict bx = B.x, *__restrict by = B.y, *__restrict bz = B.z, *__restrict bq = B.q;
  const double *__restrict bmx = B.mx, *__restrict bmy = B.my, *__restrict bmz = B.mz;
  std::size_t zeros = 0;
  for (std::size_t i = 0; i < na; ++i) {
    const double xi = A.x[i] - sh[0], yi = A.y[i] - sh[1], zi = A.z[i] - sh[2], qi = A.q ? A.q[i] : 0.0;
    const double uxi = DIP ? A.mx[i] : 0.0, uyi = DIP ? A.my[i] : 0.0, uzi = DIP ? A.mz[i] : 0.0;
    double p = 0, ax = 0, ay = 0, az = 0, hxx = 0, hyy = 0, hzz = 0, hxy = 0, hxz = 0, hyz = 0;
    long nz = 0;
    const std::size_t j0 = self ? i + 1 : 0;
    double *__restrict pb = RB.pot, *__restrict gxb = RB.gx, *__restrict gyb = RB.gy, *__restrict gzb = RB.gz;
    double *__restrict h0 = RB.hxx, *__restrict h1 = RB.hyy, *__restrict h2 = RB.hzz, *__restrict h3 = RB.hxy,
                       *__restrict h4 = RB.hxz, *__restrict h5 = RB.hyz;
#pragma omp simd reduction(+ : p, ax, ay, az, hxx, hyy, hzz, hxy, hxz, hyz, nz)
    for (std::size_t j = j0; j < nb; ++j) {
      const double dx = xi - bx[j], dy = yi - by[j], dz = zi - bz[j];
      const double r2 = dx * dx + dy * dy + dz * dz;
      const bool ok = r2 > 0.0;
      const double r2s = ok ? r2 : 1.0;
      const double invr = 1.0 / std::sqrt(r2s);
      double G, F, H, T;
      k.derivs3(r2s, invr, G, F, H, T);
      G = ok ? G : 0.0, F = ok ? F : 0.0, H = ok ? H : 0.0, T = ok ? T : 0.0;
      const double qj = bq ? bq[j] : 0.0;
      double mdj = 0, mdi = 0, ux = 0, uy = 0, uz = 0;
      if constexpr (DIP) {
        ux = bmx[j], uy = bmy[j], uz = bmz[j];
        mdj = ux * dx + uy * dy + uz * dz;
        mdi = uxi * dx + uyi * dy + uzi * dz;
      }
      if constexpr (POT) {
        p += qj * G - F * mdj;
        pb[j] += qi * G + F * mdi;
      }
      const double ca = qj * F - H * mdj, cb = qi * F + H * mdi;    // B: -(q_a F + H m_a.d) d - F m_a
      ax += ca * dx - F * ux;
      ay += ca * dy - F * uy;
      az += ca * dz - F * uz;
      gxb[j] -= cb * dx + F * uxi;
      gyb[j] -= cb * dy + F * uyi;
      gzb[j] -= cb * dz + F * uzi;
      if constexpr (HESS) {
        const double dga = qj * F - H * mdj, dda = qj * H - T * mdj;
        const double dgb = qi * F + H * mdi, ddb = qi * H + T * mdi;
        hxx += dga + dda * dx * dx - 2.0 * H * dx * ux;
        hyy += dga + dda * dy * dy - 2.0 * H * dy * uy;
        hzz += dga + dda * dz * dz - 2.0 * H * dz * uz;
        hxy += dda * dx * dy - H * (dx * uy + ux * dy);
        hxz += dda * dx * dz - H * (dx * uz + ux * dz);
        hyz += dda * dy * dz - H * (dy * uz + uy * dz);
        h0[j] += dgb + ddb * dx * dx + 2.0 * H * dx * uxi;
        h1[j] += dgb + ddb * dy * dy + 2.0 * H * dy * uyi;
        h2[j] += dgb + ddb * dz * dz + 2.0 * H * dz * uzi;
        h3[j] += ddb * dx * dy + H * (dx * uyi + uxi * dy);
        h4[j] += ddb * dx * dz + H * (dx * uzi + uxi * dz);
        h5[j] += ddb * dy * dz + H * (dy * uzi + uyi * dz);
      }
      nz += ok ? 0 : 1;
    }
    if constexpr (POT) RA.pot[i] += p;
    RA.gx[i] += ax;
    RA.gy[i] += ay;
    RA.gz[i] += az;
    if constexpr (HESS) {
      RA.hxx[i] += hxx, RA.hyy[i] += hyy, RA.hzz[i] += hzz;
      RA.hxy[i] += hxy, RA.hxz[i] += hxz, RA.hyz[i] += hyz;
    }
    zeros += (std::size_t) nz;
  }
  if (n_zero) *n_zero += 2 * zeros + (self ? na : 0);
}

template <class K, bool POT>
inline void p2p_dipole_mutual(const K &k, bool self, const PointSpan &A, const ResultSpan &RA, const PointSpan &B,
                              const ResultSpan &RB, const double sh[3], std::size_t *n_zero)
{
  if constexpr (!has_derivs3<K>::value) {
    (void) k, (void) self, (void) A, (void) RA, (void) B, (void) RB, (void) sh, (void) n_zero;
    throw std::invalid_argument("kifmm: this kernel has no third derivatives (derivs3): no dipoles");
  } else {
    const bool dip = A.mx != nullptr, hess = RA.hxx != nullptr;
    if (dip && hess) p2p_dipole_mutual_loop<K, POT, true, true>(k, self, A, RA, B, RB, sh, n_zero);
    else if (dip) p2p_dipole_mutual_loop<K, POT, true, false>(k, self, A, RA, B, RB, sh, n_zero);
    else if (hess) p2p_dipole_mutual_loop<K, POT, false, true>(k, self, A, RA, B, RB, sh, n_zero);
    else p2p_dipole_mutual_loop<K, POT, false, false>(k, self, A, RA, B, RB, sh, n_zero);
  }
}

}    // namespace kifmm
