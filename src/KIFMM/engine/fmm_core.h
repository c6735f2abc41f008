// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Templated FMM core: FmmEvaluator<Kernel> implements kifmm::Evaluator for any kernel type
// following kernels.h (tests instantiate it with their own kernel). Passes:
//   tree (octree.h) -> lists (interaction_lists.h) -> operators (operator_cache.h) ->
//   upward P2M/M2M -> M2L (FFT, m2l_fft.h) -> X (P2L) -> downward L2L -> leaf pass:
//   P2P over U, W (M2P, or P2P for small leaves), L2P.
// When sources and targets are the same points (N-body), the U pairs are evaluated mutually:
// each unordered pair of adjacent leaves once for both sides (p2p_mutual.h, MutualPlan).
// Every pass is OpenMP-parallel over cells; each cell (or target leaf) writes only its own
// data and each target accumulates its contributions in a fixed order, so results do not
// depend on the number of threads.
#pragma once

#include "communicator.h"
#include "distributed.h"
#include "interaction_lists.h"
#include "kernel_scaling.h"
#include "kifmm.h"
#include "m2l_fft.h"
#include "mutual_tasks.h"
#include "octree.h"
#include "operator_cache.h"
#include "operators.h"
#include "p2p.h"
#include "p2p_mutual.h"
#include "periodic.h"
#include "periodic_grid.h"
#include "surface.h"

#include <omp.h>

#include <algorithm>
#include <memory>
#include <vector>

namespace kifmm {

// Engine default leaf size (max points per leaf) for an order; see calibration.cpp.
int default_leaf_size(int order);

// Points of nonzero strength: xyz/q are redirected to copies in kxyz/kq when some strengths
// are zero (else left as they are); returns their number.
inline std::size_t nonzero_sources(std::size_t n, const double *&xyz, const double *&q, std::vector<double> &kxyz,
                                   std::vector<double> &kq)
{
  std::size_t nz = 0;
  for (std::size_t j = 0; j < n; ++j) nz += q[j] == 0.0;
  if (nz == 0) return n;
  kxyz.reserve(3 * (n - nz));
  kq.reserve(n - nz);
  for (std::size_t j = 0; j < n; ++j)
    if (q[j] != 0.0) {
      kxyz.insert(kxyz.end(), xyz + 3 * j, xyz + 3 * j + 3);
      kq.push_back(q[j]);
    }
  xyz = kxyz.data();
  q = kq.data();
  return kq.size();
}

template <class K> class FmmEvaluator : public Evaluator {
 public:
  FmmEvaluator(const K &k, const KernelSpec &spec, const Options &opt) : k_(k), spec_(spec), opt_(opt)
  {
    p_ = std::min(std::max(opt_.order, 2), 16);
    opt_.order = p_;
    if (opt_.leaf_size <= 0) opt_.leaf_size = default_leaf_size(p_);
    nsurf_ = surface_size(p_);
    inner_ = unit_surface(p_, kRadiusInner);
    outer_ = unit_surface(p_, kRadiusOuter);
  }

  void evaluate(std::size_t n_src, const double *src_xyz, const double *src_q, std::size_t n_trg,
                const double *trg_xyz, double *pot, double *grad) override;
  void evaluate_distributed(Communicator &comm, std::size_t n, const double *xyz, const double *q, double *pot,
                            double *grad) override;
  const Stats &stats() const override { return stats_; }
  const KernelSpec &kernel() const override { return spec_; }
  const Options &options() const override { return opt_; }
  void set_root(const double center[3], double half_width) override;

  // Internals of the last evaluation (tests).
  const Octree &tree() const { return tree_; }
  const InteractionLists &lists() const { return lists_; }

 private:
  K k_;
  KernelSpec spec_;
  Options opt_;
  Stats stats_;
  int p_ = 6, nsurf_ = 0;
  SurfacePoints inner_, outer_;
  Octree tree_;
  InteractionLists lists_;
  std::vector<std::shared_ptr<const OperatorSet>> ops_;    // per level
  std::vector<double> scale_;                              // per level: G(h u) = s G_unit(u)
  std::unique_ptr<M2LTransform> fft_;
  // sorted points (structure of arrays)
  std::vector<double> sx_, sy_, sz_, sq_, tx_, ty_, tz_, tp_, tgx_, tgy_, tgz_;
  std::vector<double> up_equiv_, dn_check_, dn_equiv_, xhat_, yhat_;
  std::vector<char> has_local_;
  std::vector<char> up_mask_;    // distributed: cells whose upward density is computed (empty = all)
  std::vector<double> frontier_buf_;    // distributed: densities of the frontier cells (reduced)

  double *up(int c) { return &up_equiv_[(std::size_t) c * nsurf_]; }
  double *dcheck(int c) { return &dn_check_[(std::size_t) c * nsurf_]; }
  double *dequiv(int c) { return &dn_equiv_[(std::size_t) c * nsurf_]; }
  void cell_surface(int c, const SurfacePoints &unit, SurfacePoints &out) const
  {
    double ctr[3];
    tree_.center(tree_.cells[c], ctr);
    box_surface(unit, ctr, tree_.half_width(tree_.cells[c].level), out);
  }
  // X list of a small target leaf: direct P2P (cost n_src*n_trg) beats P2L (n_src*nsurf)
  bool x_direct(int b) const { return tree_.cells[b].leaf() && (int) tree_.cells[b].gtrg <= nsurf_; }
  void setup_operators(double &t_setup);
  // P2M/M2M for levels l_hi down to l_lo (m2m_only: non-leaf cells only)
  void upward(int l_hi, int l_lo, bool m2m_only);
  void sorted_copies(std::size_t ns, const double *sxyz, const double *sq, std::size_t nt, const double *txyz);
  // after the lists: tree sizes into the stats, operators of every level (precompute time)
  void tree_stats_and_operators();
  // zero densities, check values and target accumulators for n_trg targets
  void reset_accumulators(std::size_t n_trg);
  // target results (sorted order) back to input order
  void results_to_input_order(std::size_t n_trg, double *pot, double *grad) const;
  void m2l();
  void p2l();
  void downward();
  void leaf_pass(bool want_pot, bool want_grad);
  // mutual near field (sources = targets): open boundaries use mutual_, periodic plists_
  MutualPlan mutual_;
  std::size_t mutual_near(bool want_pot, const std::vector<MutualPair> &pairs, const std::vector<int> &color_off,
                          const std::vector<int> &self_leaves, double L);
  // periodic boundaries (periodic.h, periodic_core.h)
  PeriodicImageLists plists_;
  std::shared_ptr<const LatticeTable> lattice_;
  std::vector<int> plattice_;
  std::vector<double> pwrap_src_, pwrap_trg_;
  double periodic_quad_ = 0.0, periodic_moments_[5] = {0, 0, 0, 0, 0};    // Laplace background part
  int first_level() const { return opt_.periodic ? 0 : 2; }    // first level with expansions
  void periodic_wrap(std::size_t ns, const double *&sxyz, std::size_t nt, const double *&txyz);
  // own_sources: sources with sorted input index below it enter the background moments
  // (distributed: this rank's own sources; the moments are then summed over ranks)
  void periodic_far(std::size_t own_sources = SIZE_MAX);
  void periodic_near(bool want_pot);
  void periodic_m2l_top(int level);    // levels 1, 2: colleague slots of one parent summed
  void periodic_background_moments(double quad, const double c[3], std::size_t own_sources);
  void add_periodic_background(bool want_pot, const double c[3]);
  // periodic single-level grid of opt_.periodic_grid^3 cells (periodic_grid.h, periodic_grid_core.h)
  std::shared_ptr<const GridKernel> grid_kernel_;
  std::vector<int> grid_src_begin_, grid_trg_begin_;    // per cell, sorted order (+ end)
  std::vector<int> grid_own_end_;                       // per cell: end of its own sources
  GridBuffer grid_spectra_;                             // spectra of all cells (convolution)
  void evaluate_grid(std::size_t ns, const double *sxyz, const double *sq, std::size_t nt, const double *txyz,
                     double *pot, double *grad, bool same_points);
  void evaluate_grid_distributed(Communicator &comm, std::size_t n, const double *xyz, const double *q, double *pot,
                                 double *grad);
  int grid_cell_of(const double *x) const;
  int grid_neighbour(int b, int dx, int dy, int dz, signed char sh[3]) const;
  void grid_bin(std::size_t ns, const double *sxyz, const double *sq, std::size_t nt, const double *txyz,
                bool same_points, std::size_t own_sources);
  void grid_passes(Communicator *comm, std::size_t own_sources, bool want_pot, bool same_points);
  // M2L layout of level l: source cells (children of a target parent's colleague) and target
  // cells (V non-empty) in slots of xhat_/yhat_ (sized here), and per parent of level l-1 the
  // spectra of its 8 children (xtab/ytab, nullptr where absent). False if no target.
  bool m2l_level_layout(int l, std::vector<int> &sources, std::vector<int> &targets,
                        std::vector<const double *> &xtab, std::vector<double *> &ytab);
};

template <class K>
bool FmmEvaluator<K>::m2l_level_layout(int l, std::vector<int> &sources, std::vector<int> &targets,
                                       std::vector<const double *> &xtab, std::vector<double *> &ytab)
{
  const auto &cells = tree_.cells;
  const int b0 = tree_.level_begin[l], b1 = tree_.level_begin[l + 1];
  const int p0 = tree_.level_begin[l - 1], p1 = tree_.level_begin[l];
  std::vector<int> src_slot(b1 - b0, -1), trg_slot(b1 - b0, -1);
  sources.clear();
  targets.clear();
  for (int b = b0; b < b1; ++b) {
    if (lists_.V.size(b) == 0) continue;
    trg_slot[b - b0] = (int) targets.size();
    targets.push_back(b);
    for (const int *a = lists_.V.begin(b); a != lists_.V.end(b); ++a)
      if (src_slot[*a - b0] < 0) {
        src_slot[*a - b0] = 0;
        sources.push_back(*a);
      }
  }
  if (targets.empty()) return false;
  std::sort(sources.begin(), sources.end());
  for (std::size_t i = 0; i < sources.size(); ++i) src_slot[sources[i] - b0] = (int) i;
  const int nf = fft_->nfreq();
  xhat_.resize(sources.size() * 2 * nf);
  yhat_.assign(targets.size() * 2 * nf, 0.0);
  xtab.assign((std::size_t) (p1 - p0) * 8, nullptr);
  ytab.assign((std::size_t) (p1 - p0) * 8, nullptr);
  for (int c = b0; c < b1; ++c) {
    const int par = cells[c].parent - p0;
    int oct = 0;
    while (cells[cells[c].parent].child[oct] != c) ++oct;
    if (src_slot[c - b0] >= 0) xtab[(std::size_t) par * 8 + oct] = &xhat_[(std::size_t) src_slot[c - b0] * 32];
    if (trg_slot[c - b0] >= 0) ytab[(std::size_t) par * 8 + oct] = &yhat_[(std::size_t) trg_slot[c - b0] * 32];
  }
  return true;
}

template <class K> void FmmEvaluator<K>::setup_operators(double &t_setup)
{
  const int nl = tree_.depth + 1;
  ops_.assign(nl, nullptr);
  scale_.assign(nl, 1.0);
  for (int l = 0; l < nl; ++l) {
    double s;
    const UnitKernel uk = make_unit_kernel(k_, tree_.half_width(l), s);
    scale_[l] = s;
    if (l < first_level()) continue;    // levels 0,1 carry no expansions (non-periodic)
    if (level_independent_operators<K>() && l > 0 && ops_[l - 1]) {
      ops_[l] = ops_[l - 1];
      continue;
    }
    ops_[l] = get_operator_set(uk, p_, opt_.cache_dir, &t_setup);
  }
  std::size_t bytes = 0;
  for (int l = 0; l < nl; ++l)
    if (ops_[l] && (l == 0 || ops_[l] != ops_[l - 1])) bytes += ops_[l]->bytes();
  stats_.operator_bytes = bytes;
  if (!fft_ || fft_->p() != p_) fft_ = std::make_unique<M2LTransform>(p_);
}

// Cells of a level are processed in chunks of kBatch; within a chunk, operators act on many
// vectors at once (GEMM): P2M pseudo-inverse on all leaf check potentials, M2M grouped by
// child octant. Each chunk writes only its own cells.
template <class K> void FmmEvaluator<K>::upward(int l_hi, int l_lo, bool m2m_only)
{
  const auto &cells = tree_.cells;
  constexpr int kBatch = 64;
  for (int l = std::min(l_hi, tree_.depth); l >= std::max(l_lo, first_level()); --l) {
    const OperatorSet &op = *ops_[l];
    const double inv_s = 1.0 / scale_[l];
    std::vector<int> list;
    for (int c = tree_.level_begin[l]; c < tree_.level_begin[l + 1]; ++c)
      if (cells[c].gsrc > 0 && !(m2m_only && cells[c].leaf()) && (up_mask_.empty() || up_mask_[c])) list.push_back(c);
    const int n = (int) list.size(), nchunks = (n + kBatch - 1) / kBatch;
#pragma omp parallel if (nchunks > 1)
    {
      SurfacePoints surf;
      std::vector<double> chk, eq, xb;
      std::vector<int> lv, nl, sel;
#pragma omp for schedule(dynamic, 1)
      for (int ch = 0; ch < nchunks; ++ch) {
        lv.clear();
        nl.clear();
        for (int i = ch * kBatch; i < std::min(n, (ch + 1) * kBatch); ++i) (cells[list[i]].leaf() ? lv : nl).push_back(list[i]);
        if (!lv.empty()) {    // P2M
          chk.assign((std::size_t) nsurf_ * lv.size(), 0.0);
          for (std::size_t j = 0; j < lv.size(); ++j) {
            const Cell &C = cells[lv[j]];
            cell_surface(lv[j], outer_, surf);
            const std::size_t b = C.src_begin;
            p2p<K, true, false, false>(k_, nsurf_, surf.x.data(), surf.y.data(), surf.z.data(), C.n_src(), &sx_[b],
                                       &sy_[b], &sz_[b], &sq_[b], &chk[j * nsurf_], nullptr, nullptr, nullptr);
          }
          eq.resize(chk.size());
          apply_pinv_batch(op.uc2e_a, op.uc2e_b, nsurf_, op.rank, chk.data(), (int) lv.size(), eq.data(), inv_s);
          for (std::size_t j = 0; j < lv.size(); ++j) std::copy(&eq[j * nsurf_], &eq[(j + 1) * nsurf_], up(lv[j]));
        }
        if (!nl.empty()) {    // M2M by octant
          eq.assign((std::size_t) nsurf_ * nl.size(), 0.0);
          for (int oct = 0; oct < 8; ++oct) {
            sel.clear();
            for (std::size_t j = 0; j < nl.size(); ++j) {
              const int c = cells[nl[j]].child[oct];
              if (c >= 0 && cells[c].gsrc > 0) sel.push_back((int) j);
            }
            if (sel.empty()) continue;
            xb.resize((std::size_t) nsurf_ * sel.size());
            for (std::size_t k = 0; k < sel.size(); ++k) {
              const double *src = up(cells[nl[sel[k]]].child[oct]);
              std::copy(src, src + nsurf_, &xb[k * nsurf_]);
            }
            chk.resize(xb.size());
            matmat(op.m2m[oct].data(), nsurf_, nsurf_, xb.data(), (int) sel.size(), chk.data(), 1.0, false);
            for (std::size_t k = 0; k < sel.size(); ++k) {
              double *dst = &eq[sel[k] * nsurf_];
              const double *y = &chk[k * nsurf_];
              for (int i = 0; i < nsurf_; ++i) dst[i] += y[i];
            }
          }
          for (std::size_t j = 0; j < nl.size(); ++j) std::copy(&eq[j * nsurf_], &eq[(j + 1) * nsurf_], up(nl[j]));
        }
      }
    }
  }
}

// sorted structure-of-arrays copies of the points (tree_.src_order / trg_order)
template <class K>
void FmmEvaluator<K>::sorted_copies(std::size_t ns, const double *sxyz, const double *sq, std::size_t n_trg,
                                    const double *trg_xyz)
{
  sx_.resize(ns);
  sy_.resize(ns);
  sz_.resize(ns);
  sq_.resize(ns);
  tx_.resize(n_trg);
  ty_.resize(n_trg);
  tz_.resize(n_trg);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < ns; ++i) {
    const std::size_t j = tree_.src_order[i];
    sx_[i] = sxyz[3 * j];
    sy_[i] = sxyz[3 * j + 1];
    sz_[i] = sxyz[3 * j + 2];
    sq_[i] = sq[j];
  }
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n_trg; ++i) {
    const std::size_t j = tree_.trg_order[i];
    tx_[i] = trg_xyz[3 * j];
    ty_[i] = trg_xyz[3 * j + 1];
    tz_[i] = trg_xyz[3 * j + 2];
  }
}

template <class K> void FmmEvaluator<K>::tree_stats_and_operators()
{
  stats_.depth = tree_.depth;
  stats_.n_cells = tree_.cells.size();
  stats_.n_leaves = tree_.leaves.size();
  double t_setup = 0;
  setup_operators(t_setup);
  stats_.t_precompute = t_setup;
}

template <class K> void FmmEvaluator<K>::reset_accumulators(std::size_t n_trg)
{
  const std::size_t nc = tree_.cells.size();
  up_equiv_.assign(nc * nsurf_, 0.0);
  dn_check_.assign(nc * nsurf_, 0.0);
  dn_equiv_.assign(nc * nsurf_, 0.0);
  has_local_.assign(nc, 0);
  tp_.assign(n_trg, 0.0);
  tgx_.assign(n_trg, 0.0);
  tgy_.assign(n_trg, 0.0);
  tgz_.assign(n_trg, 0.0);
}

template <class K> void FmmEvaluator<K>::results_to_input_order(std::size_t n_trg, double *pot, double *grad) const
{
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n_trg; ++i) {
    const std::size_t j = tree_.trg_order[i];
    if (pot) pot[j] = tp_[i];
    if (grad) {
      grad[3 * j] = tgx_[i];
      grad[3 * j + 1] = tgy_[i];
      grad[3 * j + 2] = tgz_[i];
    }
  }
}

template <class K> void FmmEvaluator<K>::m2l()
{
  const auto &cells = tree_.cells;
  const int nf = fft_->nfreq();
  std::vector<double> &xhat = xhat_, &yhat = yhat_;    // members: no page faults on reuse
  std::vector<const double *> xtab;
  std::vector<double *> ytab;
  std::vector<std::pair<int, int>> pairs[27];
  std::vector<int> sources, targets;
  for (int l = std::max(first_level(), 1); l <= tree_.depth; ++l) {
    if (opt_.periodic && l <= 2) {    // periodic_core.h
      periodic_m2l_top(l);
      continue;
    }
    const int p0 = tree_.level_begin[l - 1], p1 = tree_.level_begin[l];
    if (!m2l_level_layout(l, sources, targets, xtab, ytab)) continue;
    const int nsrc = (int) sources.size(), ntrg = (int) targets.size();
    const std::size_t xstride = (std::size_t) nsrc * 32, ystride = (std::size_t) ntrg * 32;
    for (auto &v : pairs) v.clear();
    for (int pc = p0; pc < p1; ++pc) {
      const bool has_trg = [&] {
        for (int o = 0; o < 8; ++o)
          if (ytab[(std::size_t) (pc - p0) * 8 + o]) return true;
        return false;
      }();
      if (!has_trg) continue;
      const auto &col = lists_.colleagues[pc];
      for (int sl = 0; sl < 27; ++sl) {
        const int cc = col[sl];
        if (sl == 13 || cc < 0 || cells[cc].leaf()) continue;
        bool has_src = false;
        for (int o = 0; o < 8; ++o) has_src = has_src || xtab[(std::size_t) (cc - p0) * 8 + o];
        if (has_src) pairs[sl].emplace_back(pc - p0, cc - p0);
      }
    }
#pragma omp parallel if (nsrc > 4)
    {
      M2LTransform::Workspace ws(*fft_);
#pragma omp for schedule(dynamic, 8)
      for (int i = 0; i < nsrc; ++i) fft_->forward(up(sources[i]), &xhat[(std::size_t) i * 32], xstride, ws);
    }
    const double *kern = ops_[l]->m2l_hat.data();
    const int nblocks = nf / 16;
    const int per = std::max(1, std::min(4, nblocks / (4 * omp_get_max_threads())));
#pragma omp parallel for schedule(dynamic, 1) if (ntrg > 8)
    for (int bb = 0; bb < nblocks; bb += per)
      m2l_parent_pairs(nf, kern, bb, std::min(nblocks, bb + per), pairs, xtab.data(), xstride, ytab.data(), ystride);
    const double s = scale_[l];
#pragma omp parallel if (ntrg > 4)
    {
      M2LTransform::Workspace ws(*fft_);
#pragma omp for schedule(dynamic, 8)
      for (int i = 0; i < ntrg; ++i) {
        fft_->inverse_add(&yhat[(std::size_t) i * 32], ystride, dcheck(targets[i]), s, ws);
        has_local_[targets[i]] = 1;
      }
    }
  }
}

template <class K> void FmmEvaluator<K>::p2l()
{
  const auto &cells = tree_.cells;
  const int n = (int) cells.size();
#pragma omp parallel
  {
    SurfacePoints surf;
#pragma omp for schedule(dynamic, 4)
    for (int b = 0; b < n; ++b) {
      if (lists_.X.size(b) == 0 || x_direct(b)) continue;
      cell_surface(b, inner_, surf);
      double *chk = dcheck(b);
      for (const int *a = lists_.X.begin(b); a != lists_.X.end(b); ++a) {
        const Cell &A = cells[*a];
        const std::size_t s0 = A.src_begin;
        p2p<K, true, false, false>(k_, nsurf_, surf.x.data(), surf.y.data(), surf.z.data(), A.n_src(), &sx_[s0],
                                   &sy_[s0], &sz_[s0], &sq_[s0], chk, nullptr, nullptr, nullptr);
      }
      has_local_[b] = 1;
    }
  }
}

template <class K> void FmmEvaluator<K>::downward()
{
  const auto &cells = tree_.cells;
  constexpr int kBatch = 64;
  for (int l = first_level(); l <= tree_.depth; ++l) {
    const OperatorSet &op = *ops_[l];
    const double inv_s = 1.0 / scale_[l];
    std::vector<int> list;
    for (int c = tree_.level_begin[l]; c < tree_.level_begin[l + 1]; ++c) {
      if (cells[c].n_trg() == 0) continue;
      if (l > first_level() && has_local_[cells[c].parent]) has_local_[c] = 1;
      if (has_local_[c]) list.push_back(c);
    }
    const int n = (int) list.size(), nchunks = (n + kBatch - 1) / kBatch;
#pragma omp parallel if (nchunks > 1)
    {
      std::vector<double> chk, eq, xb, yb;
      std::vector<int> sel;
#pragma omp for schedule(dynamic, 1)
      for (int ch = 0; ch < nchunks; ++ch) {
        const int i0 = ch * kBatch, m = std::min(n, (ch + 1) * kBatch) - i0;
        chk.resize((std::size_t) nsurf_ * m);
        for (int j = 0; j < m; ++j) std::copy(dcheck(list[i0 + j]), dcheck(list[i0 + j]) + nsurf_, &chk[(std::size_t) j * nsurf_]);
        if (l > first_level()) {    // L2L by octant, from the parents' downward equivalents
          for (int oct = 0; oct < 8; ++oct) {
            sel.clear();
            for (int j = 0; j < m; ++j) {
              const Cell &C = cells[list[i0 + j]];
              if ((int) (C.prefix & 7) == oct && has_local_[C.parent]) sel.push_back(j);
            }
            if (sel.empty()) continue;
            xb.resize((std::size_t) nsurf_ * sel.size());
            for (std::size_t k = 0; k < sel.size(); ++k) {
              const double *src = dequiv(cells[list[i0 + sel[k]]].parent);
              std::copy(src, src + nsurf_, &xb[k * nsurf_]);
            }
            yb.resize(xb.size());
            matmat(ops_[l - 1]->l2l[oct].data(), nsurf_, nsurf_, xb.data(), (int) sel.size(), yb.data(), scale_[l - 1], false);
            for (std::size_t k = 0; k < sel.size(); ++k) {
              double *dst = &chk[(std::size_t) sel[k] * nsurf_];
              const double *y = &yb[k * nsurf_];
              for (int i = 0; i < nsurf_; ++i) dst[i] += y[i];
            }
          }
        }
        eq.resize(chk.size());
        apply_pinv_batch(op.dc2e_a, op.dc2e_b, nsurf_, op.rank, chk.data(), m, eq.data(), inv_s);
        for (int j = 0; j < m; ++j) std::copy(&eq[(std::size_t) j * nsurf_], &eq[(std::size_t) (j + 1) * nsurf_], dequiv(list[i0 + j]));
      }
    }
  }
}

template <class K> void FmmEvaluator<K>::leaf_pass(bool want_pot, bool want_grad)
{
  (void) want_grad;
  const auto &cells = tree_.cells;
  const int nleaf = (int) tree_.leaves.size();
  std::vector<std::size_t> zeros(nleaf, 0);
  double t0 = omp_get_wtime();
  // near field: U list; source ranges of U cells that are contiguous in the sorted source
  // array are merged into one longer loop. Sources = targets: each pair of leaves once
  if (mutual_.active) {
    stats_.mutual_pairs = mutual_.pairs.size();
    stats_.coincident_pairs += mutual_near(want_pot, mutual_.pairs, mutual_.color_off, mutual_.self_leaves, 0.0);
  }
  // (a partial plan leaves the U entries with an unmarked leaf to the one-sided loop)
  const bool all_mutual = mutual_.active && !mutual_.partial;
#pragma omp parallel if (!all_mutual)
  {
    std::vector<std::pair<uint32_t, uint32_t>> ranges;
#pragma omp for schedule(dynamic, 1)
    for (int li = 0; li < nleaf; ++li) {
      const int b = tree_.leaves[li];
      const Cell &B = cells[b];
      if (B.n_trg() == 0 || all_mutual) continue;
      const bool b_mutual = mutual_.partial && mutual_.leaf_mutual[b];
      ranges.clear();
      for (const int *a = lists_.U.begin(b); a != lists_.U.end(b); ++a)
        if (!(b_mutual && mutual_.leaf_mutual[*a])) ranges.emplace_back(cells[*a].src_begin, cells[*a].src_end);
      std::sort(ranges.begin(), ranges.end());
      std::size_t nr = 0;
      for (std::size_t i = 0; i < ranges.size(); ++i) {
        if (nr > 0 && ranges[nr - 1].second == ranges[i].first) ranges[nr - 1].second = ranges[i].second;
        else ranges[nr++] = ranges[i];
      }
      const std::size_t t0i = B.trg_begin;
      for (std::size_t r = 0; r < nr; ++r) {
        const std::size_t s0 = ranges[r].first, ns = ranges[r].second - ranges[r].first;
        p2p_pg<K, true>(k_, want_pot, B.n_trg(), &tx_[t0i], &ty_[t0i], &tz_[t0i], ns, &sx_[s0], &sy_[s0], &sz_[s0],
                        &sq_[s0], &tp_[t0i], &tgx_[t0i], &tgy_[t0i], &tgz_[t0i], &zeros[li]);
      }
    }
  }
  double t1 = omp_get_wtime();
  stats_.t_p2p += t1 - t0;
  // W list: M2P (or P2P when the source leaf has fewer points than a surface)
#pragma omp parallel
  {
    SurfacePoints surf;
#pragma omp for schedule(dynamic, 1)
    for (int li = 0; li < nleaf; ++li) {
      const int b = tree_.leaves[li];
      const Cell &B = cells[b];
      if (B.n_trg() == 0 || lists_.W.size(b) == 0) continue;
      const std::size_t t0i = B.trg_begin;
      for (const int *a = lists_.W.begin(b); a != lists_.W.end(b); ++a) {
        const Cell &A = cells[*a];
        if (mutual_.active && A.leaf() && (int) A.gtrg <= mutual_.w_direct_max && (int) A.gsrc <= mutual_.w_direct_max)
          continue;    // in the mutual pairs (with the dual X entry)
        if ((int) A.gsrc <= nsurf_) {    // direct is cheaper than M2P (subtree sources are contiguous)
          const std::size_t s0 = A.src_begin;
          p2p_pg<K, false>(k_, want_pot, B.n_trg(), &tx_[t0i], &ty_[t0i], &tz_[t0i], A.n_src(), &sx_[s0], &sy_[s0],
                           &sz_[s0], &sq_[s0], &tp_[t0i], &tgx_[t0i], &tgy_[t0i], &tgz_[t0i]);
        } else {
          cell_surface(*a, inner_, surf);
          p2p_pg<K, false>(k_, want_pot, B.n_trg(), &tx_[t0i], &ty_[t0i], &tz_[t0i], nsurf_, surf.x.data(),
                           surf.y.data(), surf.z.data(), up(*a), &tp_[t0i], &tgx_[t0i], &tgy_[t0i], &tgz_[t0i]);
        }
      }
    }
  }
  // X entries of small target leaves, evaluated directly instead of P2L (see p2l())
#pragma omp parallel for schedule(dynamic, 1)
  for (int li = 0; li < nleaf; ++li) {
    const int b = tree_.leaves[li];
    const Cell &B = cells[b];
    if (B.n_trg() == 0 || !x_direct(b)) continue;
    if (mutual_.active && mutual_.w_direct_max >= nsurf_) continue;    // in the mutual pairs
    const std::size_t t0i = B.trg_begin;
    for (const int *a = lists_.X.begin(b); a != lists_.X.end(b); ++a) {
      const Cell &A = cells[*a];
      const std::size_t s0 = A.src_begin;
      p2p_pg<K, false>(k_, want_pot, B.n_trg(), &tx_[t0i], &ty_[t0i], &tz_[t0i], A.n_src(), &sx_[s0], &sy_[s0],
                       &sz_[s0], &sq_[s0], &tp_[t0i], &tgx_[t0i], &tgy_[t0i], &tgz_[t0i]);
    }
  }
  double t2 = omp_get_wtime();
  stats_.t_wx += t2 - t1;
  // L2P
#pragma omp parallel
  {
    SurfacePoints surf;
#pragma omp for schedule(dynamic, 1)
    for (int li = 0; li < nleaf; ++li) {
      const int b = tree_.leaves[li];
      const Cell &B = cells[b];
      if (B.n_trg() == 0 || !has_local_[b]) continue;
      const std::size_t t0i = B.trg_begin;
      cell_surface(b, outer_, surf);
      p2p_pg<K, false>(k_, want_pot, B.n_trg(), &tx_[t0i], &ty_[t0i], &tz_[t0i], nsurf_, surf.x.data(),
                       surf.y.data(), surf.z.data(), dequiv(b), &tp_[t0i], &tgx_[t0i], &tgy_[t0i], &tgz_[t0i]);
    }
  }
  stats_.t_downward += omp_get_wtime() - t2;
  std::size_t z = 0;
  for (auto v : zeros) z += v;
  stats_.coincident_pairs += z;
}

// Mutual near field: each leaf with itself, then the pairs of adjacent leaves in color order
// (a color's pairs share no leaf). Every target accumulates in the fixed order self, color 0,
// 1, ..., so results do not depend on the threads. L: length of the periodic cell (pair shifts
// are in units of L). Returns the coincident pairs.
template <class K>
std::size_t FmmEvaluator<K>::mutual_near(bool want_pot, const std::vector<MutualPair> &pairs,
                                         const std::vector<int> &color_off, const std::vector<int> &self,
                                         double L)
{
  const auto &cells = tree_.cells;
  auto run = [&](int a, int b, const double *sh, bool self_pair) -> std::size_t {
    const Cell &A = cells[a], &B = cells[b];
    // positions and strengths by the source ranges, accumulators by the target ranges (the
    // same points in the same order; the same ranges too unless ghosts are sources)
    const std::size_t i0 = A.src_begin, j0 = B.src_begin, ti = A.trg_begin, tj = B.trg_begin;
    std::size_t z = 0;
    if (want_pot)
      p2p_mutual<K, true>(k_, self_pair, A.n_src(), &sx_[i0], &sy_[i0], &sz_[i0], &sq_[i0], &tp_[ti], &tgx_[ti],
                          &tgy_[ti], &tgz_[ti], B.n_src(), &sx_[j0], &sy_[j0], &sz_[j0], &sq_[j0], &tp_[tj],
                          &tgx_[tj], &tgy_[tj], &tgz_[tj], sh, &z);
    else
      p2p_mutual<K, false>(k_, self_pair, A.n_src(), &sx_[i0], &sy_[i0], &sz_[i0], &sq_[i0], &tp_[ti], &tgx_[ti],
                           &tgy_[ti], &tgz_[ti], B.n_src(), &sx_[j0], &sy_[j0], &sz_[j0], &sq_[j0], &tp_[tj],
                           &tgx_[tj], &tgy_[tj], &tgz_[tj], sh, &z);
    return z;
  };
  (void) color_off;    // the pairs are stored by color; run_mutual_tasks keeps that order per leaf
  return run_mutual_tasks(cells.size(), self, pairs, [&](int a, int b, const signed char *s, bool self_pair) {
    const double sh[3] = {s[0] * L, s[1] * L, s[2] * L};
    return run(a, b, sh, self_pair);
  });
}

template <class K>
void FmmEvaluator<K>::evaluate(std::size_t n_src, const double *src_xyz, const double *src_q, std::size_t n_trg,
                               const double *trg_xyz, double *pot, double *grad)
{
  stats_ = Stats{};
  stats_.n_targets = n_trg;
  if (n_trg == 0) return;
  if (pot) std::fill(pot, pot + n_trg, 0.0);
  if (grad) std::fill(grad, grad + 3 * n_trg, 0.0);
  if (!pot && !grad) return;
  double t = omp_get_wtime();
  // drop zero-strength sources
  std::vector<double> kxyz, kq;
  const double *sxyz = src_xyz, *sq = src_q;
  const std::size_t ns = nonzero_sources(n_src, sxyz, sq, kxyz, kq);
  stats_.n_sources = ns;
  if (ns == 0) return;
  const bool same_arrays = src_xyz == trg_xyz;
  if (opt_.periodic) periodic_wrap(ns, sxyz, n_trg, trg_xyz);
  if (opt_.periodic && opt_.periodic_grid > 0) {
    evaluate_grid(ns, sxyz, sq, n_trg, trg_xyz, pot, grad, same_arrays && ns == n_src && n_src == n_trg);
    if (same_arrays && n_src == n_trg && stats_.coincident_pairs >= ns) stats_.coincident_pairs -= ns;
    return;
  }
  const RootBox root = evaluation_root(opt_.fixed_root, opt_.root_center, opt_.root_half_width,
                                       !level_independent_operators<K>(), ns, sxyz, n_trg, trg_xyz);
  build_octree(tree_, root, ns, sxyz, n_trg, trg_xyz, opt_.leaf_size, opt_.max_depth);
  sorted_copies(ns, sxyz, sq, n_trg, trg_xyz);
  double t1 = omp_get_wtime();
  stats_.t_tree = t1 - t;
  if (opt_.periodic) build_periodic_interaction_lists(tree_, lists_, plists_);
  else build_interaction_lists(tree_, lists_);
  // N-body (the sources are the targets, same order): mutual near field
  mutual_.clear();
  if (!opt_.periodic && ns == n_trg && tree_.src_order == tree_.trg_order && sx_ == tx_ && sy_ == ty_ && sz_ == tz_)
    plan_mutual_open(tree_, lists_, mutual_, nsurf_);    // U, and W/X pairs of small leaves
  double t2 = omp_get_wtime();
  stats_.t_lists = t2 - t1;
  tree_stats_and_operators();
  double t3 = omp_get_wtime();
  reset_accumulators(n_trg);
  upward(tree_.depth, first_level(), false);
  double t4 = omp_get_wtime();
  stats_.t_upward = t4 - t3;
  m2l();
  double t5 = omp_get_wtime();
  stats_.t_m2l = t5 - t4;
  p2l();
  if (opt_.periodic) periodic_far();
  double t6 = omp_get_wtime();
  stats_.t_wx = t6 - t5;
  downward();
  stats_.t_downward = omp_get_wtime() - t6;
  leaf_pass(pot != nullptr, grad != nullptr);
  mutual_.clear();    // (evaluate_distributed's leaf pass is one-sided)
  if (opt_.periodic) periodic_near(pot != nullptr);

  results_to_input_order(n_trg, pot, grad);
  // self pairs (same arrays) are not coincident pairs
  if (same_arrays && n_src == n_trg && stats_.coincident_pairs >= ns) stats_.coincident_pairs -= ns;
  stats_.tree_bytes = tree_.bytes() + lists_.bytes() +
      sizeof(double) * (up_equiv_.size() + dn_check_.size() + dn_equiv_.size() + xhat_.capacity() + yhat_.capacity() +
                        sx_.size() * 4 + tx_.size() * 7);
}

}    // namespace kifmm

#include "periodic_core.h"       // periodic passes (member templates)
#include "periodic_grid_core.h"  // periodic single-level grid (member template)
#include "distributed_core.h"    // distributed evaluation (member template)
