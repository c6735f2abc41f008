// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Steps of FmmEvaluator<K> for periodic boundaries (periodic_steps(); included at the end of
// fmm_core.h; see periodic.h):
//   periodic_wrap        : points wrapped into the cell (the fixed root)
//   periodic_lists       : the lists with the PeriodicImages policy (image entries in plists_)
//   periodic_plan_mutual : mutual near field of the U pairs, images included
//   periodic_m2l         : levels 1-2 with summed slot kernels (periodic_m2l_top), then the
//                          shared M2L of the levels below
//   periodic_far         : image X entries (P2L with shifted check surfaces) and the root's
//                          far-image lattice operator, before the downward pass
//   periodic_near        : image U, W, X entries with shifted target coordinates, after the leaf
//                          pass; Laplace: the non-harmonic part of the lattice operator
#pragma once

#include "fmm_core.h"
#include "p2p_mutual.h"
#include "periodic.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <type_traits>

namespace kifmm {

template <class K> void FmmEvaluator<K>::set_root(const double center[3], double half_width)
{
  opt_.fixed_root = true;
  for (int d = 0; d < 3; ++d) opt_.root_center[d] = center[d];
  opt_.root_half_width = half_width;
  for (int d = 0; d < 3; ++d) opt_.root_shape[d] = 1.0;
}

template <class K> void FmmEvaluator<K>::set_root_box(const double center[3], const double half_widths[3])
{
  const double h = std::max(half_widths[0], std::max(half_widths[1], half_widths[2]));
  if (!(h > 0) || !(std::min(half_widths[0], std::min(half_widths[1], half_widths[2])) > 0))
    throw std::invalid_argument("kifmm: the root box needs positive half-widths");
  set_root(center, h);
  for (int d = 0; d < 3; ++d) opt_.root_shape[d] = half_widths[d] == h ? 1.0 : half_widths[d] / h;
}

template <class K>
void FmmEvaluator<K>::periodic_wrap(std::size_t ns, const double *&sxyz, std::size_t nt, const double *&txyz)
{
  if (!opt_.fixed_root || !(opt_.root_half_width > 0))
    throw std::invalid_argument("kifmm: periodic evaluation needs the periodic cell as fixed root");
  const int dims = opt_.periodic_dims;
  if (dims != 3 && dims != 2) throw std::invalid_argument("kifmm: Options::periodic_dims must be 3 or 2");
  if (dims == 2 && !grid_)
    throw std::invalid_argument("kifmm: a slab (periodic_dims 2) needs the single-level grid (periodic_grid > 0)");
  const bool same = sxyz == txyz && ns == nt;
  wrap_into_cell(ns, sxyz, opt_.root_center, opt_.root_half_width, pwrap_src_, opt_.root_shape, dims);
  sxyz = pwrap_src_.data();
  if (same) {
    txyz = sxyz;
  } else {
    wrap_into_cell(nt, txyz, opt_.root_center, opt_.root_half_width, pwrap_trg_, opt_.root_shape, dims);
    txyz = pwrap_trg_.data();
  }
  if (dims == 2) {    // a slab: every point within the cell's z extent
    const double zlo = opt_.root_center[2] - opt_.root_half_width * opt_.root_shape[2];
    const double zhi = opt_.root_center[2] + opt_.root_half_width * opt_.root_shape[2];
    auto check = [&](std::size_t n, const double *x) {
      for (std::size_t i = 0; i < n; ++i)
        if (!(x[3 * i + 2] >= zlo && x[3 * i + 2] <= zhi))
          throw std::invalid_argument("kifmm: a point lies outside the slab's z extent (periodic_dims 2)");
    };
    check(ns, sxyz);
    if (!same) check(nt, txyz);
  }
}

template <class K> typename FmmEvaluator<K>::BoundarySteps FmmEvaluator<K>::periodic_steps()
{
  return {0, &FmmEvaluator::periodic_wrap, &FmmEvaluator::periodic_lists, &FmmEvaluator::periodic_plan_mutual,
          &FmmEvaluator::periodic_m2l, &FmmEvaluator::periodic_far, &FmmEvaluator::periodic_near};
}

// Sources and targets are the same points (same order, same coordinates): the near field (U
// lists, images included) is evaluated pair by pair for both leaves (periodic_near). Otherwise,
// distributed: the pairs of the leaves in own_only, the other U entries one-sided.
template <class K> void FmmEvaluator<K>::periodic_plan_mutual(const std::vector<char> *own_only)
{
  mutual_.clear();
  if (same_sorted_points()) plan_mutual_near(tree_, lists_, plists_);
  if (own_only && !plists_.mutual) plan_mutual_near(tree_, lists_, plists_, own_only);
}

template <class K> void FmmEvaluator<K>::periodic_m2l()
{
  for (int l = 1; l <= std::min(2, tree_.depth); ++l) periodic_m2l_top(l);
  m2l_levels(3);
}

template <class K> void FmmEvaluator<K>::periodic_far(std::size_t own_sources, Communicator *comm)
{
  periodic_image_p2l();
  periodic_root_operator();
  // Laplace: the lattice operator's quadratic part (2pi/3V) sum_j q_j |x - y_j|^2, from the
  // moments of the sources about the cell center (applied at the targets in periodic_near)
  const double h0 = tree_.root.half_width;
  periodic_background_moments(lattice_->quad / (h0 * h0 * h0), tree_.root.center, own_sources);
  if (comm) {    // distributed: this rank's own sources' moments, summed over ranks
    const double tm = omp_get_wtime();
    comm->allreduce_sum(periodic_moments_, 5);
    stats_.t_comm += omp_get_wtime() - tm;
  }
}

// X entries with an image shift: P2L onto the target's check surface moved by -shift * L
template <class K> void FmmEvaluator<K>::periodic_image_p2l()
{
  const auto &cells = tree_.cells;
  const double L[3] = {tree_.period(0), tree_.period(1), tree_.period(2)};
  const int n = (int) cells.size();
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
          x[i] = surf.x[i] - s[0] * L[0];
          y[i] = surf.y[i] - s[1] * L[1];
          z[i] = surf.z[i] - s[2] * L[2];
        }
        const Cell &A = cells[plists_.X.idx[e]];
        p2p<K, true, false, false>(k_, {(std::size_t) nsurf_, x.data(), y.data(), z.data()}, source_span(A), {chk});
      }
      has_local_[b] = 1;
    }
  }
}

// images beyond the first shell: one operator at the root (tabulated on the M2L lattice)
template <class K> void FmmEvaluator<K>::periodic_root_operator()
{
  const double h0 = tree_.root.half_width;
  KernelSpec unit;    // Laplace, or Yukawa with kappa * h0 (unit root)
  if constexpr (std::is_same_v<K, YukawaKernel>) unit = KernelSpec{KernelType::Yukawa, k_.kappa * h0};
  else if constexpr (!std::is_same_v<K, LaplaceKernel>)
    throw std::invalid_argument("kifmm: periodic boundaries need a Laplace or Yukawa kernel");
  const double t0 = omp_get_wtime();
  lattice_ = lattice_table(unit, p_, tree_.root.shape);
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
}

// Laplace: the quadratic part quad sum_j q_j |x - y_j|^2 of the lattice sum (periodic.h), from
// the moments of the sources about the cell center c (sorted sources with input index below
// own_sources; distributed: this rank's own, the moments are then summed over ranks); a dipole
// adds mu_j . grad_y of that term
template <class K>
void FmmEvaluator<K>::periodic_background_moments(double quad, const double c[3], std::size_t own_sources)
{
  periodic_quad_ = quad;
  for (double &v : periodic_moments_) v = 0.0;
  if (periodic_quad_ == 0.0) return;
  for (std::size_t j = 0; j < sq_.size(); ++j) {
    if (tree_.src_order[j] >= own_sources) continue;
    const double dx = sx_[j] - c[0], dy = sy_[j] - c[1], dz = sz_[j] - c[2];
    periodic_moments_[0] += sq_[j];
    periodic_moments_[1] += sq_[j] * dx;
    periodic_moments_[2] += sq_[j] * dy;
    periodic_moments_[3] += sq_[j] * dz;
    periodic_moments_[4] += sq_[j] * (dx * dx + dy * dy + dz * dz);
    if (dip_mu_) {    // a dipole is the limit of a charge pair: mu . grad_y of q |x - y|^2
      periodic_moments_[1] += smx_[j];
      periodic_moments_[2] += smy_[j];
      periodic_moments_[3] += smz_[j];
      periodic_moments_[4] += 2.0 * (smx_[j] * dx + smy_[j] * dy + smz_[j] * dz);
    }
  }
}

template <class K> void FmmEvaluator<K>::add_periodic_background(bool want_pot, const double c[3])
{
  if (periodic_quad_ == 0.0) return;
  // a sum_j q_j |x - y_j|^2 = a (Q |x-c|^2 - 2 (x-c).D + S2); gradient 2a (Q (x-c) - D)
  const double a = periodic_quad_, *m = periodic_moments_;
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < tp_.size(); ++i) {
    const double dx = tx_[i] - c[0], dy = ty_[i] - c[1], dz = tz_[i] - c[2];
    if (want_pot) tp_[i] += a * (m[0] * (dx * dx + dy * dy + dz * dz) - 2 * (dx * m[1] + dy * m[2] + dz * m[3]) + m[4]);
    tgx_[i] += 2 * a * (m[0] * dx - m[1]);
    tgy_[i] += 2 * a * (m[0] * dy - m[2]);
    tgz_[i] += 2 * a * (m[0] * dz - m[3]);
  }
  if (hess_)    // second derivatives: 2 a Q on the diagonal
    for (int d = 0; d < 3; ++d)
      for (double &h : th_[d]) h += 2 * a * m[0];
}

namespace periodic_top {

// The M2L pairs of one of the levels 1, 2 grouped by slot set: for every target parent, the
// set of colleague slots (bit mask) at which it sees one source parent; pairs[g]: the (target
// parent, source parent) pairs (indices from the level's first parent) of mask[g].
struct SlotGroups {
  std::vector<uint32_t> mask;
  std::vector<std::vector<std::pair<int, int>>> pairs;
};

inline SlotGroups slot_groups(const Octree &tree, const InteractionLists &lists, int l,
                              const std::vector<const double *> &xtab, const std::vector<double *> &ytab)
{
  const auto &cells = tree.cells;
  const int p0 = tree.level_begin[l - 1], p1 = tree.level_begin[l];
  SlotGroups gr;
  for (int pc = p0; pc < p1; ++pc) {
    bool has_trg = false;
    for (int o = 0; o < 8; ++o) has_trg = has_trg || ytab[(std::size_t) (pc - p0) * 8 + o];
    if (!has_trg) continue;
    const auto &col = lists.colleagues[pc];
    std::vector<std::pair<int, uint32_t>> by_src;    // source parent -> slots
    for (int sl = 0; sl < 27; ++sl) {
      const int cc = col[sl];
      if (sl == 13 || cc < 0 || cells[cc].leaf()) continue;
      bool has_src = false;
      for (int o = 0; o < 8; ++o) has_src = has_src || xtab[(std::size_t) (cc - p0) * 8 + o];
      if (!has_src) continue;
      auto it = std::find_if(by_src.begin(), by_src.end(), [&](const auto &e) { return e.first == cc; });
      if (it == by_src.end()) by_src.emplace_back(cc, uint32_t(1) << sl);
      else it->second |= uint32_t(1) << sl;
    }
    for (const auto &[cc, mask] : by_src) {
      std::size_t g = 0;
      while (g < gr.mask.size() && gr.mask[g] != mask) ++g;
      if (g == gr.mask.size()) {
        gr.mask.push_back(mask);
        gr.pairs.emplace_back();
      }
      gr.pairs[g].emplace_back(pc - p0, cc - p0);
    }
  }
  return gr;
}

// M2L kernel indices of every (group, source child, target child): the slots of the group
inline std::vector<std::vector<int>> kernel_ids(const std::vector<uint32_t> &group_mask)
{
  const int ngroup = (int) group_mask.size();
  std::vector<std::vector<int>> kid((std::size_t) ngroup * 64);
  for (int g = 0; g < ngroup; ++g)
    for (int sl = 0; sl < 27; ++sl) {
      if (!(group_mask[g] >> sl & 1)) continue;
      const int o[3] = {sl / 9 - 1, (sl / 3) % 3 - 1, sl % 3 - 1};
      for (int sc = 0; sc < 8; ++sc)
        for (int tc = 0; tc < 8; ++tc) {
          int d[3];
          for (int a = 0; a < 3; ++a) d[a] = ((tc >> a) & 1) - 2 * o[a] - ((sc >> a) & 1);
          const int id = m2l_offset_index(d[0], d[1], d[2]);
          if (id >= 0) kid[(std::size_t) g * 64 + sc * 8 + tc].push_back(id);
        }
    }
  return kid;
}

// summed kernel chunk of frequency block blk over the kernels ids into k[32]
inline void sum_kernels(const double *kern, const std::vector<int> &ids, int blk, double *k)
{
  const double *kb = kern + (std::size_t) blk * kM2LKernels * 32;
  if (ids.empty()) {
    std::fill(k, k + 32, 0.0);
    return;
  }
  const double *first = kb + (std::size_t) ids[0] * 32;
  for (int f = 0; f < 32; ++f) k[f] = first[f];
  for (std::size_t q = 1; q < ids.size(); ++q) {
    const double *src = kb + (std::size_t) ids[q] * 32;
#pragma omp simd
    for (int f = 0; f < 32; ++f) k[f] += src[f];
  }
}

// Hadamard products of one frequency block (offsets xo, yo in the spectra) for the pairs of one
// group with the group's summed kernels kg ([source child * 8 + target child][32]); nonzero:
// per (source child, target child) of the group, whether any kernel is summed there.
inline void multiply_group(const double *kg, const std::vector<std::pair<int, int>> &pairs, const char *nonzero,
                           const double *const *xtab, double *const *ytab, std::size_t xo, std::size_t yo)
{
  for (const auto &pr : pairs) {
    double *const *y = ytab + 8 * (std::size_t) pr.first;
    const double *const *x = xtab + 8 * (std::size_t) pr.second;
    for (int tc = 0; tc < 8; ++tc) {
      if (!y[tc]) continue;
      double *yr = y[tc] + yo, *yi = yr + 16;
      alignas(64) double ar[16], ai[16];    // accumulated over the source children
      for (int f = 0; f < 16; ++f) {
        ar[f] = yr[f];
        ai[f] = yi[f];
      }
      for (int sc = 0; sc < 8; ++sc) {
        if (!x[sc] || !nonzero[sc * 8 + tc]) continue;
        const double *kr = kg + (std::size_t) (sc * 8 + tc) * 32, *ki = kr + 16;
        const double *xr = x[sc] + xo, *xi = xr + 16;
#pragma omp simd aligned(ar, ai : 64)
        for (int f = 0; f < 16; ++f) {
          ar[f] += kr[f] * xr[f] - ki[f] * xi[f];
          ai[f] += kr[f] * xi[f] + ki[f] * xr[f];
        }
      }
      for (int f = 0; f < 16; ++f) {
        yr[f] = ar[f];
        yi[f] = ai[f];
      }
    }
  }
}

}    // namespace periodic_top

// M2L of the periodic levels 1 and 2, whose parents (1 and 2 per side) are their own
// colleagues' images: the colleague slots of a parent that hold the same source parent (with
// different shifts) are summed into one kernel per (source child, target child) in frequency
// space, so every (target parent, source parent) pair is multiplied once instead of once per
// slot (level 2: 56 parent pairs instead of 208; level 1: 1 instead of 26). Sources, targets,
// transforms and the order of accumulation per target are otherwise those of m2l_levels().
template <class K> void FmmEvaluator<K>::periodic_m2l_top(int l)
{
  const int nf = fft_->nfreq();
  std::vector<int> sources, targets;
  std::vector<const double *> xtab;
  std::vector<double *> ytab;
  if (!m2l_level_layout(l, sources, targets, xtab, ytab)) return;
  const int nsrc = (int) sources.size(), ntrg = (int) targets.size();
  const std::size_t xstride = (std::size_t) nsrc * 32, ystride = (std::size_t) ntrg * 32;
  const periodic_top::SlotGroups groups = periodic_top::slot_groups(tree_, lists_, l, xtab, ytab);
  const std::vector<std::vector<int>> kid = periodic_top::kernel_ids(groups.mask);
  const int ngroup = (int) groups.mask.size();
  std::vector<char> nonzero(kid.size());
  for (std::size_t q = 0; q < kid.size(); ++q) nonzero[q] = !kid[q].empty();
#pragma omp parallel if (nsrc > 4)
  {
    M2LTransform::Workspace ws(*fft_);
#pragma omp for schedule(dynamic, 8)
    for (int i = 0; i < nsrc; ++i) fft_->forward(up(sources[i]), &xhat_[(std::size_t) i * 32], xstride, ws);
  }
  const int nblocks = nf / 16;
  const std::vector<const double *> cached = periodic_top_kernels(l, groups.mask, kid, nblocks);
#pragma omp parallel for schedule(dynamic, 1)
  for (int blk = 0; blk < nblocks; ++blk) {
    const std::size_t xo = blk * xstride, yo = blk * ystride;
    for (int g = 0; g < ngroup; ++g)
      periodic_top::multiply_group(cached[g] + (std::size_t) blk * 64 * 32, groups.pairs[g],
                                   &nonzero[(std::size_t) g * 64], xtab.data(), ytab.data(), xo, yo);
  }
  const double s = scale_[l];
#pragma omp parallel if (ntrg > 4)
  {
    M2LTransform::Workspace ws(*fft_);
#pragma omp for schedule(dynamic, 8)
    for (int i = 0; i < ntrg; ++i) {
      fft_->inverse_add(&yhat_[(std::size_t) i * 32], ystride, dcheck(targets[i]), s, ws);
      has_local_[targets[i]] = 1;
    }
  }
}

// Summed slot kernels of the groups of level l (one pointer per group), kept across evaluations
// in plists_.top_kernels
// (at most 8 masks x 64 x nfreq complex: 36 MB at p = 10, 99 MB at p = 14; summing them per
// block during the products instead doubled the evaluation time of small periodic trees at
// p >= 11).
template <class K>
std::vector<const double *> FmmEvaluator<K>::periodic_top_kernels(int l, const std::vector<uint32_t> &group_mask,
                                                                  const std::vector<std::vector<int>> &kid,
                                                                  int nblocks)
{
  const int ngroup = (int) group_mask.size();
  std::vector<const double *> cached(ngroup, nullptr);
  const double *kern = ops_[l]->m2l_hat.data();
  auto &cache = plists_.top_kernels;
  if (cache.size() > 16) cache.clear();
  for (int g = 0; g < ngroup; ++g) {
    std::size_t e = 0;
    while (e < cache.size() && !(cache[e].ops.get() == ops_[l].get() && cache[e].mask == group_mask[g])) ++e;
    if (e == cache.size()) {
      PeriodicImageLists::TopKernel t;
      t.ops = ops_[l];
      t.mask = group_mask[g];
      t.hat.resize((std::size_t) nblocks * 64 * 32);
#pragma omp parallel for schedule(static)
      for (int blk = 0; blk < nblocks; ++blk)
        for (int st = 0; st < 64; ++st)
          periodic_top::sum_kernels(kern, kid[(std::size_t) g * 64 + st], blk, &t.hat[((std::size_t) blk * 64 + st) * 32]);
      cache.push_back(std::move(t));
    }
    cached[g] = cache[e].hat.data();
  }
  return cached;
}

template <class K> void FmmEvaluator<K>::periodic_near(bool want_pot)
{
  const auto &cells = tree_.cells;
  const double L[3] = {tree_.period(0), tree_.period(1), tree_.period(2)};
  const int nleaf = (int) tree_.leaves.size();
  const double t_begin = omp_get_wtime();
  if (plists_.mutual) {    // each leaf with itself, then the pairs of adjacent leaves color by color
    stats_.mutual_pairs = plists_.pairs.size();
    stats_.coincident_pairs += mutual_near(want_pot, plists_.pairs, plists_.color_off, plists_.self_leaves, L);
  }
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
          x[i] = tx_[t0 + i] - s[0] * L[0];
          y[i] = ty_[t0 + i] - s[1] * L[1];
          z[i] = tz_[t0 + i] - s[2] * L[2];
        }
      };
      const PointSpan trg{nt, x.data(), y.data(), z.data(), nullptr};
      const ResultSpan res = result_span(B);
      auto direct = [&](const Cell &A) { p2p_pg<K, false>(k_, want_pot, trg, source_span(A), res); };
      for (int e = plists_.U.begin(b); e < plists_.U.end(b); ++e) {
        shifted(plists_.U.shift_of(e));
        direct(cells[plists_.U.idx[e]]);
      }
      for (int e = plists_.W.begin(b); e < plists_.W.end(b); ++e) {
        shifted(plists_.W.shift_of(e));
        const int a = plists_.W.idx[e];
        if ((int) cells[a].gsrc <= nsurf_) {
          direct(cells[a]);
        } else {
          cell_surface(a, inner_, surf);
          p2p_pg<K, false>(k_, want_pot, trg, surface_span(surf, up(a)), res);
        }
      }
      if (x_direct(b))
        for (int e = plists_.X.begin(b); e < plists_.X.end(b); ++e) {
          shifted(plists_.X.shift_of(e));
          direct(cells[plists_.X.idx[e]]);
        }
    }
  }
  stats_.t_p2p += omp_get_wtime() - t_begin;    // near field of the images (and mutual U)
  add_periodic_background(want_pot, tree_.root.center);
}

}    // namespace kifmm
