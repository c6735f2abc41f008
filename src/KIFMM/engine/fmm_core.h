// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Templated FMM core: FmmEvaluator<K> implements kifmm::Evaluator for any kernel type
// following kernels.h (tests instantiate it with their own kernel). Passes:
//   tree (octree.h) -> lists (interaction_lists.h) -> operators (operator_cache.h) ->
//   upward P2M/M2M -> M2L (FFT, m2l_fft.h) -> X (P2L) -> downward L2L -> leaf pass:
//   P2P over U, W (M2P, or P2P for small leaves), L2P.
// This file holds the class, the passes shared by every boundary and the steps of open
// boundaries. The steps that depend on the boundary (wrap, lists, mutual plan, M2L of the top
// levels, far and near images) are chosen once at construction (BoundarySteps: open here,
// periodic in periodic_core.h); the periodic single-level grid is periodic_grid_core.h, the
// distributed evaluation distributed_core.h.
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
#include <stdexcept>
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

// The same for charges and dipole moments (evaluate_dipoles): the sources with a charge or a
// moment; xyz/q/mu are redirected to copies when some have neither, or when q is null (then
// the copies' charges are zero); mu may be null (no moments, it stays null).
inline std::size_t nonzero_dipole_sources(std::size_t n, const double *&xyz, const double *&q, const double *&mu,
                                          std::vector<double> &kxyz, std::vector<double> &kq,
                                          std::vector<double> &kmu)
{
  auto strong = [&](std::size_t j) {
    return (q && q[j] != 0.0) || (mu && (mu[3 * j] != 0.0 || mu[3 * j + 1] != 0.0 || mu[3 * j + 2] != 0.0));
  };
  std::size_t keep = 0;
  for (std::size_t j = 0; j < n; ++j) keep += strong(j);
  if (keep == n && q) return n;
  kxyz.clear(), kq.clear(), kmu.clear();
  for (std::size_t j = 0; j < n; ++j)
    if (strong(j)) {
      kxyz.insert(kxyz.end(), xyz + 3 * j, xyz + 3 * j + 3);
      kq.push_back(q ? q[j] : 0.0);
      if (mu) kmu.insert(kmu.end(), mu + 3 * j, mu + 3 * j + 3);
    }
  xyz = kxyz.data();
  q = kq.data();
  if (mu) mu = kmu.data();
  return kq.size();
}

// dip_mu_ of a dipole evaluation whose moments are not (or no longer) in an input-order array:
// this rank has no local points, or their moments are already in the sorted spans
inline constexpr double kMomentsElsewhere[3] = {0.0, 0.0, 0.0};

template <class K> class FmmEvaluator : public Evaluator {
 public:
  FmmEvaluator(const K &k, const KernelSpec &spec, const Options &opt) : k_(k), spec_(spec), opt_(opt)
  {
    boundary_ = opt_.periodic ? periodic_steps() : open_steps();
    grid_ = opt_.periodic && opt_.periodic_grid > 0;
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
  void evaluate_dipoles(std::size_t n_src, const double *src_xyz, const double *src_q, const double *src_mu,
                        std::size_t n_trg, const double *trg_xyz, double *pot, double *grad, double *hess) override;
  void evaluate_dipoles_distributed(Communicator &comm, std::size_t n, const double *xyz, const double *q,
                                    const double *mu, double *pot, double *grad, double *hess) override;
  const Stats &stats() const override { return stats_; }
  const KernelSpec &kernel() const override { return spec_; }
  const Options &options() const override { return opt_; }
  void set_root(const double center[3], double half_width) override;
  void set_root_box(const double center[3], const double half_widths[3]) override;
  void periodic_virial_fields(Communicator *comm, std::size_t n, const double *xyz, const double *q, double *offset,
                              double *psi) override;
  void periodic_dipole_virial_fields(Communicator *comm, std::size_t n_src, const double *src_xyz, const double *src_q,
                                     const double *src_mu, std::size_t n_trg, const double *trg_xyz,
                                     double *src_offset, double *trg_offset, double *psi, double *chi) override;

  // Internals of the last evaluation (tests).
  const Octree &tree() const { return tree_; }
  const InteractionLists &lists() const { return lists_; }

 private:
  K k_;
  KernelSpec spec_;
  Options opt_;
  Stats stats_;
  int p_ = 6, nsurf_ = 0;
  SurfacePoints inner_, outer_;    // unit surfaces of the root's shape (surf_shape_)
  double surf_shape_[3] = {1.0, 1.0, 1.0};
  // inner_ / outer_ for the shape of this root (rectangular roots: scaled per axis)
  void shape_surfaces(const RootBox &root)
  {
    if (root.shape[0] == surf_shape_[0] && root.shape[1] == surf_shape_[1] && root.shape[2] == surf_shape_[2]) return;
    for (int d = 0; d < 3; ++d) surf_shape_[d] = root.shape[d];
    inner_ = shaped_surface(p_, kRadiusInner, surf_shape_);
    outer_ = shaped_surface(p_, kRadiusOuter, surf_shape_);
  }
  Octree tree_;
  InteractionLists lists_;
  std::vector<std::shared_ptr<const OperatorSet>> ops_;    // per level
  std::vector<double> scale_;                              // per level: G(h u) = s G_unit(u)
  std::unique_ptr<M2LTransform> fft_;
  // sorted points (structure of arrays)
  std::vector<double> sx_, sy_, sz_, sq_, tx_, ty_, tz_, tp_, tgx_, tgy_, tgz_;
  // evaluate_dipoles: the sources' dipole moments (input order while dip_mu_ is set, then
  // sorted) and the targets' second derivatives (th_[0..5] = xx yy zz xy xz yz when hess_)
  const double *dip_mu_ = nullptr;
  bool hess_ = false;
  std::vector<double> smx_, smy_, smz_, th_[6], dip_kmu_;    // dip_kmu_: compacted moments
  struct DipoleMode {    // the dipole spans for one call only (also when a pass throws)
    FmmEvaluator &e;
    ~DipoleMode() { e.dip_mu_ = nullptr, e.hess_ = false; }
  };
  // evaluate_dipoles without resetting the dipole spans (they stay for a virial field)
  void dipole_evaluation(std::size_t n_src, const double *src_xyz, const double *src_q, const double *src_mu,
                         std::size_t n_trg, const double *trg_xyz, double *pot, double *grad, double *hess);
  // the same for evaluate_dipoles_distributed (after it dip_mu_ only marks dipole mode: the
  // moments are in the sorted spans)
  void dipole_distributed_evaluation(Communicator &comm, std::size_t n, const double *xyz, const double *q,
                                     const double *mu, double *pot, double *grad, double *hess);
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
  // near-field spans of the sorted points: sources (with strengths), targets, accumulators
  PointSpan source_range(std::size_t s0, std::size_t n) const
  {
    if (dip_mu_)
      return {n, sx_.data() + s0, sy_.data() + s0, sz_.data() + s0, sq_.data() + s0, smx_.data() + s0,
              smy_.data() + s0, smz_.data() + s0};
    return {n, sx_.data() + s0, sy_.data() + s0, sz_.data() + s0, sq_.data() + s0};
  }
  PointSpan source_span(const Cell &c) const { return source_range(c.src_begin, c.n_src()); }
  PointSpan target_range(std::size_t t0, std::size_t n) const
  {
    return {n, tx_.data() + t0, ty_.data() + t0, tz_.data() + t0, nullptr};
  }
  PointSpan target_span(const Cell &c) const { return target_range(c.trg_begin, c.n_trg()); }
  ResultSpan result_at(std::size_t t0)
  {
    if (hess_)
      return {tp_.data() + t0,    tgx_.data() + t0,   tgy_.data() + t0,   tgz_.data() + t0,
              th_[0].data() + t0, th_[1].data() + t0, th_[2].data() + t0, th_[3].data() + t0,
              th_[4].data() + t0, th_[5].data() + t0};
    return {tp_.data() + t0, tgx_.data() + t0, tgy_.data() + t0, tgz_.data() + t0};
  }
  ResultSpan result_span(const Cell &c) { return result_at(c.trg_begin); }
  // surface points (with densities as strengths)
  PointSpan surface_span(const SurfacePoints &s, const double *density) const
  {
    return {(std::size_t) nsurf_, s.x.data(), s.y.data(), s.z.data(), density};
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
  // (hess: the second derivatives too, dipole mode)
  void results_to_input_order(std::size_t n_trg, double *pot, double *grad, double *hess = nullptr) const;
  // M2L of the levels l_first .. depth (one FFT kernel per colleague slot)
  void m2l_levels(int l_first);
  void p2l();
  void downward();
  void leaf_pass(bool want_pot, bool want_grad);
  // the passes after the upward one: M2L, P2L and far images, L2L, leaf pass and near images
  // (timings into stats_; own_sources, comm: see BoundarySteps::far)
  void passes_after_upward(std::size_t own_sources, Communicator *comm, bool want_pot, bool want_grad);
  // tree, lists, operators and all passes of one process's points (sources already without
  // zero strengths, wrapped into the cell when periodic); t0: start of the evaluation
  void evaluate_tree(double t0, std::size_t ns, const double *sxyz, const double *sq, std::size_t n_trg,
                     const double *trg_xyz, double *pot, double *grad);
  // the sorted sources are the sorted targets (same points, same order)
  bool same_sorted_points() const
  {
    return sx_.size() == tx_.size() && tree_.src_order == tree_.trg_order && sx_ == tx_ && sy_ == ty_ && sz_ == tz_;
  }
  // mutual near field (sources = targets): open boundaries use mutual_, periodic plists_
  MutualPlan mutual_;
  std::size_t mutual_near(bool want_pot, const std::vector<MutualPair> &pairs, const std::vector<int> &color_off,
                          const std::vector<int> &self_leaves, const double *L);

  // ---- steps that depend on the boundary, chosen at construction: open_steps() (below),
  // periodic_steps() (periodic_core.h). The shared passes call them through boundary_.
  struct BoundarySteps {
    int first_level;    // first level with expansions
    // points into the box (periodic: copies wrapped into the cell; open: unchanged)
    void (FmmEvaluator::*wrap)(std::size_t ns, const double *&sxyz, std::size_t nt, const double *&txyz);
    void (FmmEvaluator::*lists)();    // interaction lists of tree_
    // mutual near-field plan after the lists: own_only null (one process) when the sources are
    // the targets; else (distributed) the leaves that hold only own points, all of them sources
    void (FmmEvaluator::*plan_mutual)(const std::vector<char> *own_only);
    void (FmmEvaluator::*m2l)();    // M2L of every level
    // after P2L: the far images (own_sources: sources with sorted input index below it enter
    // the background moments; comm: they are summed over its ranks)
    void (FmmEvaluator::*far)(std::size_t own_sources, Communicator *comm);
    void (FmmEvaluator::*near)(bool want_pot);    // after the leaf pass: the near images
  };
  BoundarySteps boundary_;
  bool grid_ = false;    // periodic single-level grid instead of the octree
  static BoundarySteps open_steps();
  static BoundarySteps periodic_steps();
  int first_level() const { return boundary_.first_level; }
  // open boundaries
  void open_wrap(std::size_t, const double *&, std::size_t, const double *&) {}
  void open_lists() { build_interaction_lists(tree_, lists_); }
  void open_plan_mutual(const std::vector<char> *own_only);
  void open_m2l() { m2l_levels(2); }
  void open_far(std::size_t, Communicator *) {}
  void open_near(bool) {}
  // periodic boundaries (periodic.h, periodic_core.h)
  PeriodicImageLists plists_;
  std::shared_ptr<const LatticeTable> lattice_;
  std::vector<int> plattice_;
  std::vector<double> pwrap_src_, pwrap_trg_;
  double periodic_quad_ = 0.0, periodic_moments_[5] = {0, 0, 0, 0, 0};    // Laplace background part
  void periodic_wrap(std::size_t ns, const double *&sxyz, std::size_t nt, const double *&txyz);
  void periodic_lists() { build_periodic_interaction_lists(tree_, lists_, plists_); }
  void periodic_plan_mutual(const std::vector<char> *own_only);
  void periodic_m2l();
  void periodic_far(std::size_t own_sources, Communicator *comm);
  void periodic_near(bool want_pot);
  void periodic_root_operator();    // images beyond the first shell: the root's lattice operator
  void periodic_image_p2l();        // X entries with an image shift
  void periodic_m2l_top(int level);    // levels 1, 2: colleague slots of one parent summed
  std::vector<const double *> periodic_top_kernels(int l, const std::vector<uint32_t> &group_mask,
                                                   const std::vector<std::vector<int>> &kid, int nblocks);
  void periodic_background_moments(double quad, const double c[3], std::size_t own_sources);
  void add_periodic_background(bool want_pot, const double c[3]);
  // periodic single-level grid of opt_.periodic_grid^3 cells (periodic_grid.h, periodic_grid_core.h)
  std::shared_ptr<const GridKernel> grid_kernel_;
  std::vector<int> grid_src_begin_, grid_trg_begin_;    // per cell, sorted order (+ end)
  std::vector<int> grid_own_end_;                       // per cell: end of its own sources
  GridBuffer grid_spectra_;                             // spectra of all cells (convolution)
  // distributed evaluation (distributed_core.h)
  struct DistributedState;
  // evaluate_distributed and evaluate_dipoles_distributed (with moments: dipole mode is set)
  void distributed_evaluation(Communicator &comm, const LocalPoints &pts, double *pot, double *grad, double *hess);
  std::size_t distributed_sources(const DistributedData &dd, const double *&sxyz, const double *&sq,
                                  std::vector<double> &kxyz, std::vector<double> &kq);
  void distributed_first_tree(Communicator &comm, std::size_t n, DistributedState &st);
  void distributed_tree(std::size_t n, const double *xyz, DistributedState &st);
  double distributed_upward(Communicator &comm, DistributedState &st);
  std::vector<char> copied_densities(const DistributedState &st);
  std::vector<char> own_only_leaves() const;
  void fill_frontier_buf(const DistributedState &st, const std::vector<int> &local);
  std::vector<int> local_of_top(int n_top_global) const;
  void evaluate_grid(std::size_t ns, const double *sxyz, const double *sq, std::size_t nt, const double *txyz,
                     double *pot, double *grad, bool same_points);
  void evaluate_grid_distributed(Communicator &comm, const LocalPoints &pts, double *pot, double *grad,
                                 double *hess);
  int grid_cell_of(const double *x) const;
  int grid_neighbour(int b, int dx, int dy, int dz, signed char sh[3]) const;
  void grid_bin(std::size_t ns, const double *sxyz, const double *sq, std::size_t nt, const double *txyz,
                bool same_points, std::size_t own_sources);
  void grid_passes(Communicator *comm, std::size_t own_sources, bool want_pot, bool same_points);
  struct GridGeometry {
    int k[3] = {0, 0, 0}, kc = 0;                  // cells per axis, cells
    double H = 0, h = 0;                           // largest half-width of the periodic cell, of a grid cell
    double cs[3] = {1, 1, 1};                      // a grid cell's half-widths in units of h (largest 1)
    double ss[3] = {1, 1, 1};                      // its surfaces' half-widths (grid_near_depth)
    int m[3] = {1, 1, 1};                          // cells of the near field on each side, per axis
    double w[3] = {0, 0, 0}, L[3] = {0, 0, 0};     // grid cell widths, periods
    bool slab = false;                             // periodic_dims 2: open in z
  };
  static constexpr int kGridBatch = 64;            // cells per batched operator application
  GridGeometry grid_geometry() const;
  KernelSpec grid_unit_kernel(const GridGeometry &g) const;    // the grid tables' kernel (unit cell)
  void grid_center(const GridGeometry &g, int b, double ctr[3]) const;
  void grid_reduce(Communicator *comm, double *v, std::size_t m);    // sum over ranks (comm null: none)
  void grid_operators(const GridGeometry &g);
  void grid_p2m(const GridGeometry &g);
  void grid_m2l(const GridGeometry &g, const std::vector<double> &occupied, const GridKernel &gk, double s);
  // periodic virial (periodic_grid_virial_core.h): the offset-weighted field after an evaluation
  // (chi_sorted not null: with the second derivatives of the weighted potential, dipole mode)
  void grid_offset_field(Communicator *comm, double *psi_sorted, double *chi_sorted = nullptr);
  void grid_offsets(std::size_t n, const double *xyz, double *offset) const;    // from the cells' centres
  void check_virial_grid() const;
  void grid_l2p(const GridGeometry &g, bool want_pot);
  std::size_t grid_near_mutual(const GridGeometry &g, bool want_pot);
  std::size_t grid_near_one_sided(const GridGeometry &g, bool want_pot);
  // the m targets from t moved by -shift L (they see the image of a neighbour cell at +shift L)
  void grid_shifted_targets(const GridGeometry &g, std::size_t t, std::size_t m, const signed char sh[3],
                            std::vector<double> &x, std::vector<double> &y, std::vector<double> &z) const
  {
    x.resize(m);
    y.resize(m);
    z.resize(m);
    for (std::size_t i = 0; i < m; ++i) {
      x[i] = tx_[t + i] - sh[0] * g.L[0];
      y[i] = ty_[t + i] - sh[1] * g.L[1];
      z[i] = tz_[t + i] - sh[2] * g.L[2];
    }
  }
  void grid_wrap_correction(const GridGeometry &g, Communicator *comm, double quad, bool want_pot);
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
    const UnitKernel uk = make_unit_kernel(k_, tree_.half_width(l), s, tree_.root.shape);
    scale_[l] = s;
    if (l < first_level()) continue;    // levels without expansions (open: 0, 1)
    if (level_independent_operators<K>() && l > 0 && ops_[l - 1]) {
      ops_[l] = ops_[l - 1];
      continue;
    }
    // the on-disk cache holds cubic cells only (a box that changes shape would fill it)
    ops_[l] = get_operator_set(uk, p_, uk.cubic() ? opt_.cache_dir : std::string(), &t_setup);
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
            cell_surface(lv[j], outer_, surf);
            p2p<K, true, false, false>(k_, surface_span(surf, nullptr), source_span(cells[lv[j]]), {&chk[j * nsurf_]});
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
  const double *mu = dip_mu_;    // dipole moments (evaluate_dipoles), input order
  if (mu) {
    smx_.resize(ns);
    smy_.resize(ns);
    smz_.resize(ns);
  }
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
    if (mu) {
      smx_[i] = mu[3 * j];
      smy_[i] = mu[3 * j + 1];
      smz_[i] = mu[3 * j + 2];
    }
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
  for (auto &h : th_) h.assign(hess_ ? n_trg : 0, 0.0);
}

template <class K>
void FmmEvaluator<K>::results_to_input_order(std::size_t n_trg, double *pot, double *grad, double *hess) const
{
  if (!hess_) hess = nullptr;
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n_trg; ++i) {
    const std::size_t j = tree_.trg_order[i];
    if (pot) pot[j] = tp_[i];
    if (grad) {
      grad[3 * j] = tgx_[i];
      grad[3 * j + 1] = tgy_[i];
      grad[3 * j + 2] = tgz_[i];
    }
    if (hess)
      for (int c = 0; c < 6; ++c) hess[6 * j + c] = th_[c][i];
  }
}

template <class K> void FmmEvaluator<K>::m2l_levels(int l_first)
{
  const auto &cells = tree_.cells;
  const int nf = fft_->nfreq();
  std::vector<double> &xhat = xhat_, &yhat = yhat_;    // members: no page faults on reuse
  std::vector<const double *> xtab;
  std::vector<double *> ytab;
  std::vector<std::pair<int, int>> pairs[27];
  std::vector<int> sources, targets;
  for (int l = std::max(l_first, 1); l <= tree_.depth; ++l) {
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
        p2p<K, true, false, false>(k_, surface_span(surf, nullptr), source_span(cells[*a]), {chk});
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
    // Chunks hold cells of one child octant, so that L2L is one product over the whole chunk
    // (an operator is packed once per product: few columns per product would cost more in
    // packing than in arithmetic at high orders).
    const bool l2l = l > first_level();
    if (l2l)
      std::stable_sort(list.begin(), list.end(),
                       [&](int a, int b) { return (cells[a].prefix & 7) < (cells[b].prefix & 7); });
    std::vector<std::pair<int, int>> chunks;
    for (int i = 0, n = (int) list.size(); i < n;) {
      int e = i + 1;
      while (e < n && e - i < kBatch && (!l2l || (cells[list[e]].prefix & 7) == (cells[list[i]].prefix & 7))) ++e;
      chunks.emplace_back(i, e);
      i = e;
    }
    const int nchunks = (int) chunks.size();
#pragma omp parallel if (nchunks > 1)
    {
      std::vector<double> chk, eq, xb, yb;
      std::vector<int> sel;
#pragma omp for schedule(dynamic, 1)
      for (int ch = 0; ch < nchunks; ++ch) {
        const int i0 = chunks[ch].first, m = chunks[ch].second - i0;
        chk.resize((std::size_t) nsurf_ * m);
        for (int j = 0; j < m; ++j) std::copy(dcheck(list[i0 + j]), dcheck(list[i0 + j]) + nsurf_, &chk[(std::size_t) j * nsurf_]);
        if (l2l) {    // L2L from the parents' downward equivalents (one octant per chunk)
          const int oct = (int) (cells[list[i0]].prefix & 7);
          sel.clear();
          for (int j = 0; j < m; ++j)
            if (has_local_[cells[list[i0 + j]].parent]) sel.push_back(j);
          if (!sel.empty()) {
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
    stats_.coincident_pairs += mutual_near(want_pot, mutual_.pairs, mutual_.color_off, mutual_.self_leaves, nullptr);
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
      for (std::size_t r = 0; r < nr; ++r)
        p2p_pg<K, true>(k_, want_pot, target_span(B), source_range(ranges[r].first, ranges[r].second - ranges[r].first),
                        result_span(B), &zeros[li]);
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
      for (const int *a = lists_.W.begin(b); a != lists_.W.end(b); ++a) {
        const Cell &A = cells[*a];
        if (mutual_.active && A.leaf() && (int) A.gtrg <= mutual_.w_direct_max && (int) A.gsrc <= mutual_.w_direct_max)
          continue;    // in the mutual pairs (with the dual X entry)
        if ((int) A.gsrc <= nsurf_) {    // direct is cheaper than M2P (subtree sources are contiguous)
          p2p_pg<K, false>(k_, want_pot, target_span(B), source_span(A), result_span(B));
        } else {
          cell_surface(*a, inner_, surf);
          p2p_pg<K, false>(k_, want_pot, target_span(B), surface_span(surf, up(*a)), result_span(B));
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
    for (const int *a = lists_.X.begin(b); a != lists_.X.end(b); ++a)
      p2p_pg<K, false>(k_, want_pot, target_span(B), source_span(cells[*a]), result_span(B));
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
      cell_surface(b, outer_, surf);
      p2p_pg<K, false>(k_, want_pot, target_span(B), surface_span(surf, dequiv(b)), result_span(B));
    }
  }
  stats_.t_downward += omp_get_wtime() - t2;
  std::size_t z = 0;
  for (auto v : zeros) z += v;
  stats_.coincident_pairs += z;
}

// Mutual near field: each leaf with itself, then the pairs of adjacent leaves in color order
// (a color's pairs share no leaf). Every target accumulates in the fixed order self, color 0,
// 1, ..., so results do not depend on the threads. L: edges of the periodic cell (pair shifts
// are in units of them; null: open boundaries). Returns the coincident pairs.
template <class K>
std::size_t FmmEvaluator<K>::mutual_near(bool want_pot, const std::vector<MutualPair> &pairs,
                                         const std::vector<int> &color_off, const std::vector<int> &self,
                                         const double *L)
{
  const auto &cells = tree_.cells;
  auto run = [&](int a, int b, const double *sh, bool self_pair) -> std::size_t {
    const Cell &A = cells[a], &B = cells[b];
    // positions and strengths by the source ranges, accumulators by the target ranges (the
    // same points in the same order; the same ranges too unless ghosts are sources)
    const MutualSpan sa{source_span(A), result_span(A)}, sb{source_span(B), result_span(B)};
    std::size_t z = 0;
    if (want_pot) p2p_mutual<K, true>(k_, self_pair, sa, sb, sh, &z);
    else p2p_mutual<K, false>(k_, self_pair, sa, sb, sh, &z);
    return z;
  };
  (void) color_off;    // the pairs are stored by color; run_mutual_tasks keeps that order per leaf
  return run_mutual_tasks(cells.size(), self, pairs, [&](int a, int b, const signed char *s, bool self_pair, int) {
    const double sh[3] = {L ? s[0] * L[0] : 0.0, L ? s[1] * L[1] : 0.0, L ? s[2] * L[2] : 0.0};
    return run(a, b, sh, self_pair);
  });
}

template <class K>
void FmmEvaluator<K>::passes_after_upward(std::size_t own_sources, Communicator *comm, bool want_pot, bool want_grad)
{
  const double t4 = omp_get_wtime();
  (this->*boundary_.m2l)();
  const double t5 = omp_get_wtime();
  stats_.t_m2l = t5 - t4;
  p2l();
  (this->*boundary_.far)(own_sources, comm);
  const double t6 = omp_get_wtime();
  stats_.t_wx = t6 - t5;
  downward();
  stats_.t_downward = omp_get_wtime() - t6;
  leaf_pass(want_pot, want_grad);
  mutual_.clear();
  (this->*boundary_.near)(want_pot);
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
  const double t = omp_get_wtime();
  // drop zero-strength sources
  std::vector<double> kxyz, kq;
  const double *sxyz = src_xyz, *sq = src_q;
  const std::size_t ns = nonzero_sources(n_src, sxyz, sq, kxyz, kq);
  stats_.n_sources = ns;
  if (ns == 0) return;
  const bool same_arrays = src_xyz == trg_xyz;
  (this->*boundary_.wrap)(ns, sxyz, n_trg, trg_xyz);
  if (grid_) evaluate_grid(ns, sxyz, sq, n_trg, trg_xyz, pot, grad, same_arrays && ns == n_src && n_src == n_trg);
  else evaluate_tree(t, ns, sxyz, sq, n_trg, trg_xyz, pot, grad);
  // self pairs (same arrays) are not coincident pairs
  if (same_arrays && n_src == n_trg && stats_.coincident_pairs >= ns) stats_.coincident_pairs -= ns;
}

template <class K>
void FmmEvaluator<K>::evaluate_tree(double t0, std::size_t ns, const double *sxyz, const double *sq,
                                    std::size_t n_trg, const double *trg_xyz, double *pot, double *grad)
{
  const RootBox root = evaluation_root(opt_.fixed_root, opt_.root_center, opt_.root_half_width, opt_.root_shape,
                                       !level_independent_operators<K>(), ns, sxyz, n_trg, trg_xyz);
  build_octree(tree_, root, ns, sxyz, n_trg, trg_xyz, opt_.leaf_size, opt_.max_depth);
  shape_surfaces(root);
  sorted_copies(ns, sxyz, sq, n_trg, trg_xyz);
  const double t1 = omp_get_wtime();
  stats_.t_tree = t1 - t0;
  (this->*boundary_.lists)();
  (this->*boundary_.plan_mutual)(nullptr);    // N-body (the sources are the targets): mutual near field
  const double t2 = omp_get_wtime();
  stats_.t_lists = t2 - t1;
  tree_stats_and_operators();
  const double t3 = omp_get_wtime();
  reset_accumulators(n_trg);
  upward(tree_.depth, first_level(), false);
  stats_.t_upward = omp_get_wtime() - t3;
  passes_after_upward(SIZE_MAX, nullptr, pot != nullptr, grad != nullptr);
  results_to_input_order(n_trg, pot, grad);
  stats_.tree_bytes = tree_.bytes() + lists_.bytes() +
      sizeof(double) * (up_equiv_.size() + dn_check_.size() + dn_equiv_.size() + xhat_.capacity() + yhat_.capacity() +
                        sx_.size() * 4 + tx_.size() * 7);
}

// Charges and dipoles: the passes of evaluate() (tree or periodic grid) with dipole sources in
// the spans of the source points (P2M, P2L, near field) and second derivatives in the spans of
// the targets (near field, M2P, L2P); mutual near field when sources = targets; periodic
// Laplace: the dipoles' part of the background and of the grid's wrap correction.
template <class K>
void FmmEvaluator<K>::evaluate_dipoles(std::size_t n_src, const double *src_xyz, const double *src_q,
                                       const double *src_mu, std::size_t n_trg, const double *trg_xyz, double *pot,
                                       double *grad, double *hess)
{
  DipoleMode mode{*this};
  dipole_evaluation(n_src, src_xyz, src_q, src_mu, n_trg, trg_xyz, pot, grad, hess);
}

template <class K>
void FmmEvaluator<K>::dipole_evaluation(std::size_t n_src, const double *src_xyz, const double *src_q,
                                        const double *src_mu, std::size_t n_trg, const double *trg_xyz, double *pot,
                                        double *grad, double *hess)
{
  if (!has_derivs3<K>::value) throw std::invalid_argument("kifmm: this kernel has no third derivatives: no dipoles");
  stats_ = Stats{};
  stats_.n_targets = n_trg;
  if (pot) std::fill(pot, pot + n_trg, 0.0);
  if (grad) std::fill(grad, grad + 3 * n_trg, 0.0);
  if (hess) std::fill(hess, hess + 6 * n_trg, 0.0);
  if (n_trg == 0 || (!pot && !grad && !hess)) return;
  const double t = omp_get_wtime();
  std::vector<double> kxyz, kq;    // sources with a charge or a dipole (copies only when some have neither)
  const double *sxyz = src_xyz, *sq = src_q, *smu = src_mu;
  const std::size_t ns = nonzero_dipole_sources(n_src, sxyz, sq, smu, kxyz, kq, dip_kmu_);
  stats_.n_sources = ns;
  if (ns == 0) return;
  dip_mu_ = smu;
  hess_ = hess != nullptr;
  std::vector<double> g;
  double *gr = grad;
  if (!gr) {    // the second derivatives come with the gradient
    g.resize(3 * n_trg);
    gr = g.data();
  }
  const bool same_arrays = src_xyz == trg_xyz && n_src == n_trg && ns == n_src;
  (this->*boundary_.wrap)(ns, sxyz, n_trg, trg_xyz);    // periodic: into the cell (moments unchanged)
  if (grid_) evaluate_grid(ns, sxyz, sq, n_trg, trg_xyz, pot, gr, same_arrays);
  else evaluate_tree(t, ns, sxyz, sq, n_trg, trg_xyz, pot, gr);
  if (hess) results_to_input_order(n_trg, nullptr, nullptr, hess);
  if (same_arrays && stats_.coincident_pairs >= ns) stats_.coincident_pairs -= ns;    // self pairs
}

// ---- open boundaries

template <class K> typename FmmEvaluator<K>::BoundarySteps FmmEvaluator<K>::open_steps()
{
  return {2, &FmmEvaluator::open_wrap, &FmmEvaluator::open_lists, &FmmEvaluator::open_plan_mutual,
          &FmmEvaluator::open_m2l, &FmmEvaluator::open_far, &FmmEvaluator::open_near};
}

// one process: U pairs and the W/X pairs of small leaves (plan_mutual_open); distributed: the U
// pairs of the leaves in own_only (plan_mutual_partial), the rest one-sided
template <class K> void FmmEvaluator<K>::open_plan_mutual(const std::vector<char> *own_only)
{
  mutual_.clear();
  if (own_only) plan_mutual_partial(tree_, lists_, *own_only, mutual_);
  else if (same_sorted_points()) plan_mutual_open(tree_, lists_, mutual_, nsurf_);
}

}    // namespace kifmm

#include "periodic_core.h"       // periodic passes (member templates)
#include "periodic_grid_core.h"  // periodic single-level grid (member template)
#include "periodic_grid_virial_core.h"  // periodic virial on the grid (member template)
#include "distributed_core.h"    // distributed evaluation (member template)
