// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// FmmEvaluator<K>::evaluate_distributed (included at the end of fmm_core.h). The parts that
// do not depend on the kernel (root, top tree, whole-cell imports, the locally essential
// trees' requests and answers) are distributed.h/.cpp; here: when some rank needs a LET, a first
// tree over own + whole-imported points and its upward densities (what the LET answers and the
// frontier densities are made of); the evaluation tree over own + ghost points with the global
// top (extended by the LET cells) copied in, its densities (copied, received or computed), the
// exchange of the frontier densities, the top M2M, and the usual passes for this rank's targets.
// Periodic boundaries: the root is the periodic cell (every rank wraps its own points into it),
// ghosts are requested through the cell's faces too, the local lists are the periodic ones
// (image shifts), the root's lattice operator acts on the reduced root density (the same on
// every rank) and the moments of the Laplace background term are summed over ranks.
#pragma once

#include <stdexcept>

namespace kifmm {

// What the steps of one distributed evaluation pass on to each other.
template <class K> struct FmmEvaluator<K>::DistributedState {
  DistributedData dd;
  std::vector<int> slots;          // frontier cells (top indices) with densities
  std::vector<char> slot_mine;     // per slot: this rank is responsible for its density
  // with LETs: the first tree (own and whole imported points), its densities and which it has
  Octree tree1;
  std::vector<double> up1;
  std::vector<char> have1;
  double t_tree = 0, t_up1 = 0, precompute1 = 0;
};

template <class K>
void FmmEvaluator<K>::evaluate_distributed(Communicator &comm, std::size_t n, const double *xyz, const double *q,
                                           double *pot, double *grad)
{
  LocalPoints pts;
  pts.n = n, pts.xyz = xyz, pts.q = q;
  distributed_evaluation(comm, pts, pot, grad, nullptr);
}

// Charges and dipoles: the same steps with the moments carried along with the points (ghosts,
// LET points) and second derivatives at the targets (as evaluate_dipoles).
template <class K>
void FmmEvaluator<K>::evaluate_dipoles_distributed(Communicator &comm, std::size_t n, const double *xyz,
                                                   const double *q, const double *mu, double *pot, double *grad,
                                                   double *hess)
{
  DipoleMode mode{*this};
  dipole_distributed_evaluation(comm, n, xyz, q, mu, pot, grad, hess);
}

template <class K>
void FmmEvaluator<K>::dipole_distributed_evaluation(Communicator &comm, std::size_t n, const double *xyz,
                                                    const double *q, const double *mu, double *pot, double *grad,
                                                    double *hess)
{
  if (!has_derivs3<K>::value) throw std::invalid_argument("kifmm: this kernel has no third derivatives: no dipoles");
  hess_ = hess != nullptr;
  std::vector<double> zq, zmu, g;
  if (!q) zq.assign(n, 0.0);
  if (!mu) zmu.assign(3 * n, 0.0);
  if (!grad && hess) g.resize(3 * n);    // the second derivatives come with the gradient
  if (hess) std::fill(hess, hess + 6 * n, 0.0);
  LocalPoints pts;
  pts.n = n, pts.xyz = xyz, pts.q = q ? q : zq.data(), pts.mu = mu ? mu : zmu.data(), pts.moments = true;
  distributed_evaluation(comm, pts, pot, grad ? grad : (hess ? g.data() : nullptr), hess);
  if (dip_mu_) dip_mu_ = kMomentsElsewhere;    // (the local moments are gone; their sorted copies stay)
}

// The sources among this rank's local points (own, ghost and LET points; compacted copies when
// some are not sources); with moments, dip_mu_ is set to theirs (sorted_copies reads it).
template <class K>
std::size_t FmmEvaluator<K>::distributed_sources(const DistributedData &dd, const double *&sxyz, const double *&sq,
                                                 std::vector<double> &kxyz, std::vector<double> &kq)
{
  sxyz = dd.xyz.data(), sq = dd.q.data();
  if (!dd.moments) return nonzero_sources(dd.q.size(), sxyz, sq, kxyz, kq);
  const double *smu = dd.mu.empty() ? kMomentsElsewhere : dd.mu.data();
  const std::size_t ns = nonzero_dipole_sources(dd.q.size(), sxyz, sq, smu, kxyz, kq, dip_kmu_);
  dip_mu_ = smu;
  return ns;
}

template <class K>
void FmmEvaluator<K>::distributed_evaluation(Communicator &comm, const LocalPoints &pts, double *pot, double *grad,
                                             double *hess)
{
  const std::size_t n = pts.n;
  const double *xyz = pts.xyz;
  stats_ = Stats{};
  stats_.n_targets = n;
  if (pot) std::fill(pot, pot + n, 0.0);
  if (grad) std::fill(grad, grad + 3 * n, 0.0);
  comm.reset_counters();
  const double t = omp_get_wtime();
  RootBox fixed;
  if (opt_.fixed_root) {
    for (int d = 0; d < 3; ++d) fixed.center[d] = opt_.root_center[d];
    fixed.half_width = opt_.root_half_width;
    for (int d = 0; d < 3; ++d) fixed.shape[d] = opt_.root_shape[d];
  }
  {    // own points into the box (periodic: wrapped into the cell, as in serial)
    const double *sxyz = xyz;
    (this->*boundary_.wrap)(n, sxyz, n, xyz);
  }
  if (grid_) {    // single-level grid (periodic_grid_core.h)
    LocalPoints wrapped = pts;
    wrapped.xyz = xyz;
    evaluate_grid_distributed(comm, wrapped, pot, grad, hess);
    return;
  }
  DistributedState st;
  DistributedData &dd = st.dd;
  const DistributedConfig cfg{opt_.top_level, opt_.leaf_size, opt_.max_depth, nsurf_,
                              !level_independent_operators<K>(), opt_.fixed_root ? &fixed : nullptr, opt_.periodic};
  LocalPoints wrapped = pts;
  wrapped.xyz = xyz;
  distributed_setup(comm, cfg, wrapped, dd);
  stats_.t_comm = dd.t_comm;
  stats_.top_level = dd.top.top_level;
  stats_.n_sources = dd.global_sources;
  if (dd.global_sources == 0) {
    stats_.comm_bytes = comm.bytes_sent();
    return;
  }
  // Densities of the frontier cells: the responsible rank (which holds the whole cell) puts
  // its cells' into frontier_buf_, one sum over ranks (after the evaluation tree's upward pass).
  for (std::size_t f = 0; f < dd.frontier.size(); ++f) {
    const Cell &F = dd.top.cells[dd.frontier[f]];
    if (F.level >= first_level() && F.gsrc > 0) {
      st.slots.push_back(dd.frontier[f]);
      st.slot_mine.push_back(dd.responsible[f]);
    }
  }
  frontier_buf_.assign(st.slots.size() * (std::size_t) nsurf_, 0.0);
  const double ta = omp_get_wtime();    // setup done (its communication: dd.t_comm)
  st.t_tree = ta - t - dd.t_comm;
  if (dd.any_let) distributed_first_tree(comm, n, st);
  stats_.t_comm = dd.t_comm;
  stats_.ghost_bytes = dd.ghost_bytes;
  stats_.let_bytes = dd.let_bytes;
  stats_.let_cells = dd.let_cells;
  distributed_tree(n, xyz, st);
  const double t3 = omp_get_wtime();
  reset_accumulators(n);
  const double t_reduce = distributed_upward(comm, st);
  stats_.t_upward = omp_get_wtime() - t3 - t_reduce + st.t_up1;
  // near field: pairs of leaves that hold only own points (all of them sources) are evaluated
  // once for both sides, the rest one-sided (sources include ghost points); periodic: image
  // pairs too (the whole plan when sources = targets, one rank)
  const std::vector<char> own_only = own_only_leaves();
  (this->*boundary_.plan_mutual)(&own_only);
  // own sources come first in the local source array (periodic: the background moments of this
  // rank's sources, summed over ranks)
  std::size_t own_src = 0;
  for (std::size_t i = 0; i < n; ++i) own_src += pts.source(i);
  passes_after_upward(own_src, &comm, pot != nullptr, grad != nullptr);
  results_to_input_order(n, pot, grad, hess);
  // a point of nonzero strength meets itself once (not a coincident pair)
  if (stats_.coincident_pairs >= own_src) stats_.coincident_pairs -= own_src;
  stats_.tree_bytes = tree_.bytes() + lists_.bytes() +
      sizeof(double) * (up_equiv_.size() + dn_check_.size() + dn_equiv_.size() + xhat_.capacity() + yhat_.capacity() +
                        sx_.size() * 4 + tx_.size() * 7 + dd.xyz.capacity() + dd.q.capacity() + dd.mu.capacity() +
                        dd.let_density.capacity() + frontier_buf_.capacity());
  stats_.comm_bytes = comm.bytes_sent();
}

// frontier cells' densities this rank is responsible for into frontier_buf_ (local: the tree
// cell of every global top cell)
template <class K>
void FmmEvaluator<K>::fill_frontier_buf(const DistributedState &st, const std::vector<int> &local)
{
  for (std::size_t k = 0; k < st.slots.size(); ++k)
    if (st.slot_mine[k]) std::copy(up(local[st.slots[k]]), up(local[st.slots[k]]) + nsurf_, &frontier_buf_[k * nsurf_]);
}

template <class K> std::vector<int> FmmEvaluator<K>::local_of_top(int n_top_global) const
{
  std::vector<int> local(n_top_global, -1);
  for (std::size_t c = 0; c < tree_.cells.size(); ++c)
    if (tree_.top_index[c] >= 0 && tree_.top_index[c] < n_top_global) local[tree_.top_index[c]] = (int) c;
  return local;
}

// 1. (some rank needs a LET) this rank's tree over its own and whole imported points, complete
// below the frontier cells marked complete, and the upward densities below the ones it holds
// points of: for the frontier densities it is responsible for, the LETs other ranks ask for, and
// its own lists (copied into the evaluation tree). 2. locally essential trees: sent for the open
// frontier cells other ranks asked for, received below the ones this rank asked for (cells,
// densities, points). The first tree is kept in st (tree1, up1, have1).
template <class K> void FmmEvaluator<K>::distributed_first_tree(Communicator &comm, std::size_t n, DistributedState &st)
{
  DistributedData &dd = st.dd;
  const double ta = omp_get_wtime();
  std::vector<double> kxyz, kq;
  const std::size_t nl = dd.q.size();
  const double *sxyz, *sq;
  const std::size_t ns = distributed_sources(dd, sxyz, sq, kxyz, kq);
  build_octree(tree_, dd.root, ns, sxyz, nl, dd.xyz.data(), opt_.leaf_size, opt_.max_depth, &dd.top);
  shape_surfaces(dd.root);
  sorted_copies(ns, sxyz, sq, 0, nullptr);
  const double tb = omp_get_wtime();
  st.t_tree += tb - ta;
  tree_stats_and_operators();
  st.precompute1 = stats_.t_precompute;
  const std::size_t nc1 = tree_.cells.size();
  up_equiv_.assign(nc1 * nsurf_, 0.0);
  up_mask_.assign(nc1, 0);    // (cells are level-ordered: a parent before its children)
  for (std::size_t c = 0; c < nc1; ++c) {
    const int t = tree_.top_index[c];
    if (t < 0) up_mask_[c] = up_mask_[tree_.cells[c].parent];
    else if (dd.frontier_index[t] >= 0) up_mask_[c] = dd.complete[dd.frontier_index[t]] && dd.occupied[dd.frontier_index[t]];
  }
  const double t1 = omp_get_wtime();
  upward(tree_.depth, first_level(), false);
  fill_frontier_buf(st, local_of_top(dd.n_top_global));
  const double tl = omp_get_wtime();
  st.t_up1 = tl - t1;
  const double comm_before_let = dd.t_comm;
  exchange_let(comm, tree_, n, up_equiv_, nsurf_, opt_.periodic, dd);
  st.t_tree += omp_get_wtime() - tl - (dd.t_comm - comm_before_let);    // fragments
  st.tree1 = std::move(tree_);
  st.up1 = std::move(up_equiv_);
  st.have1 = std::move(up_mask_);
}

// 3. the tree of the evaluation: own, whole imported and LET points below the global top tree
// extended by the LET cells; its lists and operators
template <class K> void FmmEvaluator<K>::distributed_tree(std::size_t n, const double *xyz, DistributedState &st)
{
  DistributedData &dd = st.dd;
  std::vector<double> kxyz, kq;
  const std::size_t nl = dd.q.size();
  stats_.n_ghosts = nl - n;
  const double t2a = omp_get_wtime();
  const double *sxyz, *sq;
  const std::size_t ns = distributed_sources(dd, sxyz, sq, kxyz, kq);
  build_octree(tree_, dd.root, ns, sxyz, nl, dd.xyz.data(), opt_.leaf_size, opt_.max_depth, &dd.top);
  shape_surfaces(dd.root);
  keep_targets(tree_, n);
  sorted_copies(ns, sxyz, sq, n, xyz);
  const double t2b = omp_get_wtime();
  stats_.t_tree = st.t_tree + (t2b - t2a);
  (this->*boundary_.lists)();
  const double t2 = omp_get_wtime();
  stats_.t_lists = t2 - t2b;
  tree_stats_and_operators();
  stats_.t_precompute += st.precompute1;
}

// Upward densities of the evaluation tree: with LETs, cells of the first tree (same position,
// same points) copied and LET cells from the fragments; what a V or W list of an own cell still
// needs (cells below the top tree without a density, with their subtrees) and, without LETs, the
// frontier cells this rank is responsible for are computed here; then the frontier densities
// summed over ranks and the M2M over the global top cells with children (the same on every
// rank). Returns the time of the reduction.
template <class K> double FmmEvaluator<K>::distributed_upward(Communicator &comm, DistributedState &st)
{
  DistributedData &dd = st.dd;
  const std::size_t nc = tree_.cells.size();
  const std::vector<int> local = local_of_top(dd.n_top_global);
  const std::vector<char> has = copied_densities(st);
  // (cells below the global top tree: built from all their points here)
  auto below_top = [&](int c) { return tree_.top_index[c] < 0 || tree_.top_index[c] >= dd.n_top_global; };
  up_mask_.assign(nc, 0);
  for (const CellList *lst : {&lists_.V, &lists_.W})
    for (int a : lst->idx)
      if (below_top(a) && !has[a]) up_mask_[a] = 1;
  for (int a : plists_.W.idx)    // W entries with an image shift (periodic; else none)
    if (below_top(a) && !has[a]) up_mask_[a] = 1;
  if (!dd.any_let)
    for (std::size_t k = 0; k < st.slots.size(); ++k)
      if (st.slot_mine[k]) up_mask_[local[st.slots[k]]] = 1;
  for (std::size_t c = 1; c < nc; ++c)
    if (below_top((int) c) && !has[c] && up_mask_[tree_.cells[c].parent]) up_mask_[c] = 1;
  upward(tree_.depth, first_level(), false);
  if (!dd.any_let) fill_frontier_buf(st, local);
  const double tc = omp_get_wtime();
  comm.allreduce_sum(frontier_buf_.data(), frontier_buf_.size());
  const double t_reduce = omp_get_wtime() - tc;
  stats_.t_comm += t_reduce;
  for (std::size_t k = 0; k < st.slots.size(); ++k)
    std::copy(&frontier_buf_[k * nsurf_], &frontier_buf_[(k + 1) * nsurf_], up(local[st.slots[k]]));
  // M2M over the global top cells with children (the same on every rank)
  for (std::size_t c = 0; c < nc; ++c) {
    const int t = tree_.top_index[c];
    up_mask_[c] = t >= 0 && t < dd.n_top_global && dd.top_internal[t];
  }
  upward(dd.top.top_level - 1, first_level(), true);
  up_mask_.clear();
  return t_reduce;
}

// With LETs: the densities of the evaluation tree's cells that the first tree (same position,
// same points) or a LET fragment holds, copied into up_equiv_; returns which cells have one.
template <class K> std::vector<char> FmmEvaluator<K>::copied_densities(const DistributedState &st)
{
  const DistributedData &dd = st.dd;
  const std::size_t nc = tree_.cells.size();
  std::vector<char> has(nc, 0);
  if (!dd.any_let) return has;
  std::vector<int> in1(nc, -1);
  in1[0] = 0;
  for (std::size_t c = 1; c < nc; ++c) {
    const int p1 = in1[tree_.cells[c].parent];
    if (p1 >= 0) in1[c] = st.tree1.cells[p1].child[tree_.cells[c].prefix & 7];
  }
  for (std::size_t c = 0; c < nc; ++c) {
    const int t = tree_.top_index[c];
    if (t >= dd.n_top_global) {
      const std::size_t k = (std::size_t) (t - dd.n_top_global);
      if (dd.let_has_density[k]) {
        std::copy(&dd.let_density[k * nsurf_], &dd.let_density[(k + 1) * nsurf_], up((int) c));
        has[c] = 1;
      }
    } else if (in1[c] >= 0 && st.have1[in1[c]] && tree_.cells[c].gsrc > 0) {
      std::copy(&st.up1[(std::size_t) in1[c] * nsurf_], &st.up1[(std::size_t) (in1[c] + 1) * nsurf_], up((int) c));
      has[c] = 1;
    }
  }
  return has;
}

// leaves that hold only own points, all of them sources, in the same order as targets
template <class K> std::vector<char> FmmEvaluator<K>::own_only_leaves() const
{
  std::vector<char> own_only(tree_.cells.size(), 0);
  for (int b : tree_.leaves) {
    const Cell &B = tree_.cells[b];
    bool same = B.n_trg() > 0 && B.n_trg() == B.n_src() && B.gsrc == B.n_src() && B.gtrg == B.n_trg();
    for (uint32_t k = 0; same && k < B.n_src(); ++k)
      same = sx_[B.src_begin + k] == tx_[B.trg_begin + k] && sy_[B.src_begin + k] == ty_[B.trg_begin + k] &&
          sz_[B.src_begin + k] == tz_[B.trg_begin + k];
    own_only[b] = same;
  }
  return own_only;
}

}    // namespace kifmm
