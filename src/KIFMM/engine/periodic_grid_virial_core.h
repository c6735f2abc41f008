// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic virial on the single-level grid (Laplace; Yukawa in p p p): FmmEvaluator<K>::periodic_virial_fields (included
// at the end of fmm_core.h; the formulas are in kifmm.h at periodic_point_virial and in
// periodic_grid.h at periodic_grid_moment_kernels).
//
// For a target x in cell t and a source y in cell s (image n), x - y - n L = u - w + D_n with
// u = x - c_t, w = y - c_s and D_n = c_t - c_s - n L. The offset-weighted field
// psi_ab(x) = d_b sum_{s, n} D_n,a Phi_{s,n}(x) (Phi_{s,n}: the potential of image n of the
// sources of cell s) has
//   near part: the 26 neighbour cells (D = minus the neighbour's offset times the cell widths);
//   far part : all other images through the offset-weighted kernels, applied to the cells'
//              upward densities as the ordinary grid M2L (degree 0: no scale), then the
//              check-to-equivalent and L2P gradient of the grid;
//   background: the kernels leave out -(2 pi / 5 V) zeta_a |zeta|^2, zeta = u - w; it is added
//              here from the moments sum q, sum q w, sum q w w^T of all sources (p p p; a slab's
//              kernels are harmonic: images over the x-y lattice only, D_n,z = c_t,z - c_s,z).
#pragma once

#include "fmm_core.h"
#include "periodic.h"
#include "periodic_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>

namespace kifmm {

template <class K> void FmmEvaluator<K>::check_virial_grid() const
{
  if (!(std::is_same_v<K, LaplaceKernel> || std::is_same_v<K, YukawaKernel>) || !grid_ || opt_.periodic_dims < 2)
    throw std::invalid_argument(
        "kifmm: the periodic virial is computed for the Laplace and Yukawa kernels on the single-level "
        "grid (Options::periodic_grid > 0) with three periodic dimensions or a slab");
}

// offsets from the cells' centres (wrapped coordinates)
template <class K> void FmmEvaluator<K>::grid_offsets(std::size_t n, const double *xyz, double *offset) const
{
  std::vector<double> wrapped;
  wrap_into_cell(n, xyz, opt_.root_center, opt_.root_half_width, wrapped, opt_.root_shape, opt_.periodic_dims);
  const GridGeometry g = grid_geometry();
  for (std::size_t i = 0; i < n; ++i) {
    double c[3];
    grid_center(g, grid_cell_of(&wrapped[3 * i]), c);
    for (int d = 0; d < 3; ++d) offset[3 * i + d] = wrapped[3 * i + d] - c[d];
  }
}

template <class K>
void FmmEvaluator<K>::periodic_dipole_virial_fields(Communicator *comm, std::size_t n_src, const double *src_xyz,
                                                    const double *src_q, const double *src_mu, std::size_t n_trg,
                                                    const double *trg_xyz, double *src_offset, double *trg_offset,
                                                    double *psi, double *chi)
{
  check_virial_grid();
  const bool dist = comm && comm->size() > 1;
  if (dist && (n_src != n_trg || src_xyz != trg_xyz))
    throw std::invalid_argument("kifmm: distributed periodic_dipole_virial_fields: the sources must be the targets");
  grid_offsets(n_src, src_xyz, src_offset);
  grid_offsets(n_trg, trg_xyz, trg_offset);
  std::fill(psi, psi + 9 * n_trg, 0.0);
  std::fill(chi, chi + 18 * n_trg, 0.0);
  if (n_trg == 0 && !dist) return;
  DipoleMode mode{*this};
  std::vector<double> grad(3 * n_trg), hess(6 * n_trg);
  if (dist)
    dipole_distributed_evaluation(*comm, n_src, src_xyz, src_q, src_mu, nullptr, grad.data(), hess.data());
  else
    dipole_evaluation(n_src, src_xyz, src_q, src_mu, n_trg, trg_xyz, nullptr, grad.data(), hess.data());
  if (stats_.n_sources == 0) return;    // (distributed: a global count)
  std::vector<double> ps(9 * tx_.size(), 0.0), ch(18 * tx_.size(), 0.0);
  grid_offset_field(dist ? comm : nullptr, ps.data(), ch.data());
  for (std::size_t i = 0; i < tx_.size(); ++i) {
    std::copy(&ps[9 * i], &ps[9 * i + 9], psi + 9 * tree_.trg_order[i]);
    std::copy(&ch[18 * i], &ch[18 * i + 18], chi + 18 * tree_.trg_order[i]);
  }
}

template <class K>
void FmmEvaluator<K>::periodic_virial_fields(Communicator *comm, std::size_t n, const double *xyz, const double *q,
                                             double *offset, double *psi)
{
  check_virial_grid();
  const bool dist = comm && comm->size() > 1;
  grid_offsets(n, xyz, offset);
  std::fill(psi, psi + 9 * n, 0.0);
  std::vector<double> grad(3 * n);
  if (dist) evaluate_distributed(*comm, n, xyz, q, nullptr, grad.data());
  else if (n > 0) evaluate(n, xyz, q, n, xyz, nullptr, grad.data());
  else return;
  if (stats_.n_sources == 0) return;    // the same on every rank (a global count)
  std::vector<double> ps(9 * tx_.size(), 0.0);
  grid_offset_field(dist ? comm : nullptr, ps.data());
  for (std::size_t i = 0; i < tx_.size(); ++i) std::copy(&ps[9 * i], &ps[9 * i + 9], psi + 9 * tree_.trg_order[i]);
}

template <class K> void FmmEvaluator<K>::grid_offset_field(Communicator *comm, double *psi, double *chi)
{
  if constexpr (std::is_same_v<K, LaplaceKernel> || std::is_same_v<K, YukawaKernel>) {
    const GridGeometry g = grid_geometry();
    const std::vector<int> &sb = grid_src_begin_, &tb = grid_trg_begin_, &own_end = grid_own_end_;
    const std::size_t nt = tx_.size();
    const int kc = g.kc;
    // ---- far part: three convolutions of the upward densities (kept from the evaluation)
    const auto mk = periodic_grid_moment_kernels(grid_unit_kernel(g), g.k, p_, g.cs, g.slab);
    std::vector<double> occupied(kc);
    for (int b = 0; b < kc; ++b) occupied[b] = own_end[b] - sb[b];
    grid_reduce(comm, occupied.data(), kc);
    for (int a = 0; a < 3; ++a) {
      dn_check_.assign((std::size_t) kc * nsurf_, 0.0);
      std::fill(tgx_.begin(), tgx_.end(), 0.0);
      std::fill(tgy_.begin(), tgy_.end(), 0.0);
      std::fill(tgz_.begin(), tgz_.end(), 0.0);
      for (auto &h : th_) std::fill(h.begin(), h.end(), 0.0);
      grid_m2l(g, occupied, *mk->a[a], 1.0);
      grid_l2p(g, false);
      for (std::size_t i = 0; i < nt; ++i) {
        psi[9 * i + 3 * a] += tgx_[i];
        psi[9 * i + 3 * a + 1] += tgy_[i];
        psi[9 * i + 3 * a + 2] += tgz_[i];
        if (chi)
          for (int m = 0; m < 6; ++m) chi[18 * i + 6 * a + m] += th_[m][i];
      }
    }
    // ---- near part: the gradient of each neighbour cell's sources times the centres' offset
    const auto offsets = grid_near_offsets(g.m);
#pragma omp parallel
    {
      std::vector<double> x, y, z, gx, gy, gz, h[6];
#pragma omp for schedule(dynamic, 1)
      for (int b = 0; b < kc; ++b) {
        const std::size_t t = tb[b], m = tb[b + 1] - tb[b];
        if (m == 0) continue;
        for (const auto &o : offsets) {
          const int dx = o[0], dy = o[1], dz = o[2];
          if (dx == 0 && dy == 0 && dz == 0) continue;    // D = 0
          signed char sh[3];
          const int s = grid_neighbour(b, dx, dy, dz, sh);
          if (s < 0 || sb[s + 1] == sb[s]) continue;
          grid_shifted_targets(g, t, m, sh, x, y, z);
          gx.assign(m, 0.0);
          gy.assign(m, 0.0);
          gz.assign(m, 0.0);
          ResultSpan res{nullptr, gx.data(), gy.data(), gz.data()};
          if (chi) {
            for (auto &v : h) v.assign(m, 0.0);
            res = {nullptr,     gx.data(),   gy.data(),   gz.data(),   h[0].data(),
                   h[1].data(), h[2].data(), h[3].data(), h[4].data(), h[5].data()};
          }
          p2p_pg<K, false>(k_, false, {m, x.data(), y.data(), z.data()}, source_range(sb[s], sb[s + 1] - sb[s]), res);
          const double D[3] = {-dx * g.w[0], -dy * g.w[1], -dz * g.w[2]};
          for (std::size_t i = 0; i < m; ++i)
            for (int a = 0; a < 3; ++a) {
              double *pa = psi + 9 * (t + i) + 3 * a;
              pa[0] += D[a] * gx[i];
              pa[1] += D[a] * gy[i];
              pa[2] += D[a] * gz[i];
              if (chi)
                for (int c = 0; c < 6; ++c) chi[18 * (t + i) + 6 * a + c] += D[a] * h[c][i];
            }
        }
      }
    }
    // ---- background: d_b of sum_j q_j N_a(u - w_j), N_a(z) = -(2 pi / 5 V) z_a |z|^2
    // dipoles: minus mu . grad_z of the charge terms, from P = sum mu and R_ab = sum mu_a w_b.
    // A slab and the Yukawa kernel have none (their kernels have no background).
    if (g.slab || std::is_same_v<K, YukawaKernel>) return;
    double mom[25] = {0};    // Q, M1[3], M2[9], P[3], R[9]
    for (int b = 0; b < kc; ++b) {
      double c[3];
      grid_center(g, b, c);
      for (int j = sb[b]; j < own_end[b]; ++j) {
        const double w[3] = {sx_[j] - c[0], sy_[j] - c[1], sz_[j] - c[2]}, s = sq_[j];
        mom[0] += s;
        for (int a = 0; a < 3; ++a) {
          mom[1 + a] += s * w[a];
          for (int e = 0; e < 3; ++e) mom[4 + 3 * a + e] += s * w[a] * w[e];
        }
        if (dip_mu_) {
          const double mu[3] = {smx_[j], smy_[j], smz_[j]};
          for (int a = 0; a < 3; ++a) {
            mom[13 + a] += mu[a];
            for (int e = 0; e < 3; ++e) mom[16 + 3 * a + e] += mu[a] * w[e];
          }
        }
      }
    }
    grid_reduce(comm, mom, 25);
    constexpr double pi = 3.14159265358979323846;
    const double V = g.L[0] * g.L[1] * g.L[2], cN = -2.0 * pi / (5.0 * V);
    const double Q = mom[0], *M1 = mom + 1, *M2 = mom + 4, trM2 = M2[0] + M2[4] + M2[8];
    const double *P = mom + 13, *R = mom + 16, trR = R[0] + R[4] + R[8];
    const int ia[6] = {0, 1, 2, 0, 0, 1}, ib[6] = {0, 1, 2, 1, 2, 2};
#pragma omp parallel for schedule(static)
    for (int b = 0; b < kc; ++b) {
      double c[3];
      grid_center(g, b, c);
      for (int i = tb[b]; i < tb[b + 1]; ++i) {
        const double u[3] = {tx_[i] - c[0], ty_[i] - c[1], tz_[i] - c[2]};
        const double S = Q * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) -
            2 * (u[0] * M1[0] + u[1] * M1[1] + u[2] * M1[2]) + trM2;
        const double Pu = P[0] * u[0] + P[1] * u[1] + P[2] * u[2];
        for (int a = 0; a < 3; ++a)
          for (int e = 0; e < 3; ++e) {
            const double T = Q * u[a] * u[e] - u[a] * M1[e] - M1[a] * u[e] + M2[3 * a + e];
            // dipoles: -2 cN [P_a u_e - R_ae + P_e u_a - R_ea + delta_ae (P.u - tr R)]
            const double Dp = P[a] * u[e] - R[3 * a + e] + P[e] * u[a] - R[3 * e + a] + (a == e ? Pu - trR : 0.0);
            psi[9 * (std::size_t) i + 3 * a + e] += cN * ((a == e ? S : 0.0) + 2 * T - 2 * Dp);
          }
        if (chi)    // second derivatives: 2 cN [delta_ab z_e + delta_ae z_b + delta_be z_a] summed, minus dipoles
          for (int a = 0; a < 3; ++a)
            for (int m = 0; m < 6; ++m) {
              const int b2 = ia[m], e = ib[m];
              const double zc[3] = {Q * u[0] - M1[0], Q * u[1] - M1[1], Q * u[2] - M1[2]};
              double v = (a == b2 ? zc[e] : 0.0) + (a == e ? zc[b2] : 0.0) + (b2 == e ? zc[a] : 0.0);
              v -= (b2 == e ? P[a] : 0.0) + (a == b2 ? P[e] : 0.0) + (a == e ? P[b2] : 0.0);
              chi[18 * (std::size_t) i + 6 * a + m] += 2 * cN * v;
            }
      }
    }
  } else {
    (void) comm;
    (void) psi;
  }
}

}    // namespace kifmm
