// Periodic passes of FmmEvaluator<K> (included at the end of fmm_core.h; see periodic.h):
//   periodic_wrap : points wrapped into the cell (the fixed root)
//   periodic_far  : image X entries (P2L with shifted check surfaces) and the root's far-image
//                   lattice operator, before the downward pass
//   periodic_near : image U, W, X entries with shifted target coordinates, after the leaf pass;
//                   Laplace: the constant of the non-harmonic part of the lattice operator
#pragma once

#include "fmm_core.h"
#include "periodic.h"

#include <stdexcept>
#include <type_traits>

namespace kifmm {

template <class K> void FmmEvaluator<K>::set_root(const double center[3], double half_width)
{
  opt_.fixed_root = true;
  for (int d = 0; d < 3; ++d) opt_.root_center[d] = center[d];
  opt_.root_half_width = half_width;
}

template <class K>
void FmmEvaluator<K>::periodic_wrap(std::size_t ns, const double *&sxyz, std::size_t nt, const double *&txyz)
{
  if (!opt_.fixed_root || !(opt_.root_half_width > 0))
    throw std::invalid_argument("kifmm: periodic evaluation needs the periodic cell as fixed root");
  const bool same = sxyz == txyz && ns == nt;
  wrap_into_cell(ns, sxyz, opt_.root_center, opt_.root_half_width, pwrap_src_);
  sxyz = pwrap_src_.data();
  if (same) {
    txyz = sxyz;
  } else {
    wrap_into_cell(nt, txyz, opt_.root_center, opt_.root_half_width, pwrap_trg_);
    txyz = pwrap_trg_.data();
  }
}

template <class K> void FmmEvaluator<K>::periodic_far()
{
  const auto &cells = tree_.cells;
  const double L = 2.0 * tree_.root.half_width;
  const int n = (int) cells.size();
  // X entries with an image shift: P2L onto the target's check surface moved by -shift * L
#pragma omp parallel
  {
    SurfacePoints surf;
    std::vector<double> x, y, z;
#pragma omp for schedule(dynamic, 4)
    for (int b = 0; b < n; ++b) {
      if (plists_.X.size(b) == 0 || x_direct(b)) continue;
      cell_surface(b, inner_, surf);
      x.resize(nsurf_);
      y.resize(nsurf_);
      z.resize(nsurf_);
      double *chk = dcheck(b);
      for (int e = plists_.X.begin(b); e < plists_.X.end(b); ++e) {
        const signed char *s = plists_.X.shift_of(e);
        for (int i = 0; i < nsurf_; ++i) {
          x[i] = surf.x[i] - s[0] * L;
          y[i] = surf.y[i] - s[1] * L;
          z[i] = surf.z[i] - s[2] * L;
        }
        const Cell &A = cells[plists_.X.idx[e]];
        const std::size_t s0 = A.src_begin;
        p2p<K, true, false, false>(k_, nsurf_, x.data(), y.data(), z.data(), A.n_src(), &sx_[s0], &sy_[s0], &sz_[s0],
                                   &sq_[s0], chk, nullptr, nullptr, nullptr);
      }
      has_local_[b] = 1;
    }
  }
  // images beyond the first shell: one operator at the root (tabulated on the M2L lattice)
  const double h0 = tree_.root.half_width;
  KernelSpec unit;    // Laplace, or Yukawa with kappa * h0 (unit root)
  if constexpr (std::is_same_v<K, YukawaKernel>) unit = KernelSpec{KernelType::Yukawa, k_.kappa * h0};
  else if constexpr (!std::is_same_v<K, LaplaceKernel>)
    throw std::invalid_argument("kifmm: periodic boundaries need a Laplace or Yukawa kernel");
  const double t0 = omp_get_wtime();
  lattice_ = lattice_table(unit, p_);
  stats_.t_precompute += omp_get_wtime() - t0;
  const int p = p_, m = 2 * p - 1;
  if (plattice_.size() != 3 * (std::size_t) nsurf_) plattice_ = surface_lattice(p);
  const double *u = up(0);
  double *chk = dcheck(0);
  const double s = scale_[0];
  const double *r = lattice_->r.data();
  const int *lat = plattice_.data();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < nsurf_; ++i) {
    double acc = 0;
    const int ix = lat[3 * i] + p - 1, iy = lat[3 * i + 1] + p - 1, iz = lat[3 * i + 2] + p - 1;
    for (int k = 0; k < nsurf_; ++k)
      acc += r[((std::size_t) (ix - lat[3 * k]) * m + (iy - lat[3 * k + 1])) * m + (iz - lat[3 * k + 2])] * u[k];
    chk[i] += s * acc;
  }
  has_local_[0] = 1;
  // Laplace: the lattice operator's quadratic part (2pi/3V) sum_j q_j |x - y_j|^2, from the
  // moments of the sources about the cell center (applied at the targets in periodic_near)
  periodic_quad_ = lattice_->quad / (h0 * h0 * h0);
  for (double &v : periodic_moments_) v = 0.0;
  if (periodic_quad_ != 0.0) {
    const double *c = tree_.root.center;
    for (std::size_t j = 0; j < sq_.size(); ++j) {
      const double dx = sx_[j] - c[0], dy = sy_[j] - c[1], dz = sz_[j] - c[2];
      periodic_moments_[0] += sq_[j];
      periodic_moments_[1] += sq_[j] * dx;
      periodic_moments_[2] += sq_[j] * dy;
      periodic_moments_[3] += sq_[j] * dz;
      periodic_moments_[4] += sq_[j] * (dx * dx + dy * dy + dz * dz);
    }
  }
}

template <class K> void FmmEvaluator<K>::periodic_near(bool want_pot)
{
  const auto &cells = tree_.cells;
  const double L = 2.0 * tree_.root.half_width;
  const int nleaf = (int) tree_.leaves.size();
#pragma omp parallel
  {
    SurfacePoints surf;
    std::vector<double> x, y, z;
#pragma omp for schedule(dynamic, 1)
    for (int li = 0; li < nleaf; ++li) {
      const int b = tree_.leaves[li];
      const Cell &B = cells[b];
      if (B.n_trg() == 0) continue;
      const std::size_t t0 = B.trg_begin, nt = B.n_trg();
      x.resize(nt);
      y.resize(nt);
      z.resize(nt);
      // targets moved by -shift * L see the sources of the image at +shift * L
      auto shifted = [&](const signed char *s) {
        for (std::size_t i = 0; i < nt; ++i) {
          x[i] = tx_[t0 + i] - s[0] * L;
          y[i] = ty_[t0 + i] - s[1] * L;
          z[i] = tz_[t0 + i] - s[2] * L;
        }
      };
      double *tp = &tp_[t0], *gx = &tgx_[t0], *gy = &tgy_[t0], *gz = &tgz_[t0];
      auto direct = [&](const Cell &A) {
        const std::size_t s0 = A.src_begin;
        p2p_pg<K, false>(k_, want_pot, nt, x.data(), y.data(), z.data(), A.n_src(), &sx_[s0], &sy_[s0], &sz_[s0],
                         &sq_[s0], tp, gx, gy, gz);
      };
      for (int e = plists_.U.begin(b); e < plists_.U.end(b); ++e) {
        shifted(plists_.U.shift_of(e));
        direct(cells[plists_.U.idx[e]]);
      }
      for (int e = plists_.W.begin(b); e < plists_.W.end(b); ++e) {
        shifted(plists_.W.shift_of(e));
        const int a = plists_.W.idx[e];
        if ((int) cells[a].n_src() <= nsurf_) {
          direct(cells[a]);
        } else {
          cell_surface(a, inner_, surf);
          p2p_pg<K, false>(k_, want_pot, nt, x.data(), y.data(), z.data(), nsurf_, surf.x.data(), surf.y.data(),
                           surf.z.data(), up(a), tp, gx, gy, gz);
        }
      }
      if (x_direct(b))
        for (int e = plists_.X.begin(b); e < plists_.X.end(b); ++e) {
          shifted(plists_.X.shift_of(e));
          direct(cells[plists_.X.idx[e]]);
        }
    }
  }
  if (periodic_quad_ != 0.0) {
    // a sum_j q_j |x - y_j|^2 = a (Q |x-c|^2 - 2 (x-c).D + S2); gradient 2a (Q (x-c) - D)
    const double a = periodic_quad_, *m = periodic_moments_, *c = tree_.root.center;
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < tp_.size(); ++i) {
      const double dx = tx_[i] - c[0], dy = ty_[i] - c[1], dz = tz_[i] - c[2];
      if (want_pot) tp_[i] += a * (m[0] * (dx * dx + dy * dy + dz * dz) - 2 * (dx * m[1] + dy * m[2] + dz * m[3]) + m[4]);
      tgx_[i] += 2 * a * (m[0] * dx - m[1]);
      tgy_[i] += 2 * a * (m[0] * dy - m[2]);
      tgz_[i] += 2 * a * (m[0] * dz - m[3]);
    }
  }
}

}    // namespace kifmm
