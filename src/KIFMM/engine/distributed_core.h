// FmmEvaluator<K>::evaluate_distributed (included at the end of fmm_core.h). The setup that
// does not depend on the kernel (root, top tree, ghost import) is distributed.h/.cpp; here:
// the local tree over own + ghost points with the global top copied in, the exchange of the
// frontier densities, the top M2M, and the usual passes for this rank's targets.
// Periodic boundaries: the root is the periodic cell (every rank wraps its own points into it),
// ghosts are requested through the cell's faces too, the local lists are the periodic ones
// (image shifts), the root's lattice operator acts on the reduced root density (the same on
// every rank) and the moments of the Laplace background term are summed over ranks.
#pragma once

#include <stdexcept>

namespace kifmm {

template <class K>
void FmmEvaluator<K>::evaluate_distributed(Communicator &comm, std::size_t n, const double *xyz, const double *q,
                                           double *pot, double *grad)
{
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
  }
  if (opt_.periodic) {    // own points wrapped into the cell (as periodic_wrap does in serial)
    const double *sxyz = xyz;
    periodic_wrap(n, sxyz, n, xyz);
  }
  DistributedData dd;
  distributed_setup(comm, opt_.top_level, opt_.leaf_size, opt_.max_depth, nsurf_, !level_independent_operators<K>(),
                    opt_.fixed_root ? &fixed : nullptr, opt_.periodic, n, xyz, q, dd);
  stats_.t_comm = dd.t_comm;
  stats_.ghost_bytes = dd.ghost_bytes;
  stats_.top_level = dd.top.top_level;
  stats_.n_sources = dd.global_sources;
  auto finish = [&] { stats_.comm_bytes = comm.bytes_sent(); };
  if (dd.global_sources == 0) {
    finish();
    return;
  }
  const std::size_t nl = dd.q.size();
  stats_.n_ghosts = nl - n;
  // local sources: points of nonzero strength; local targets: all points (the ghosts count
  // for the split rule, then keep_targets drops them)
  std::vector<double> kxyz, kq;
  const double *sxyz = dd.xyz.data(), *sq = dd.q.data();
  const std::size_t ns = nonzero_sources(nl, sxyz, sq, kxyz, kq);
  build_octree(tree_, dd.root, ns, sxyz, nl, dd.xyz.data(), opt_.leaf_size, opt_.max_depth, &dd.top);
  keep_targets(tree_, n);
  sorted_copies(ns, sxyz, sq, n, xyz);
  const double t1 = omp_get_wtime();
  stats_.t_tree = t1 - t - dd.t_comm;
  if (opt_.periodic) build_periodic_interaction_lists(tree_, lists_, plists_);
  else build_interaction_lists(tree_, lists_);
  const double t2 = omp_get_wtime();
  stats_.t_lists = t2 - t1;
  tree_stats_and_operators();
  const double t3 = omp_get_wtime();
  reset_accumulators(n);
  const std::size_t nc = tree_.cells.size();
  // upward densities only where they are used: cells below the top tree that appear in a V or
  // W list of an own cell (and their subtrees, for M2M), and the frontier cells this rank is
  // responsible for; the top cells get theirs from the reduction below (no P2M of ghost-only
  // subtrees that no list uses)
  // local index of every top cell
  std::vector<int> local_of(dd.top.cells.size(), -1);
  for (std::size_t c = 0; c < nc; ++c)
    if (tree_.top_index[c] >= 0) local_of[tree_.top_index[c]] = (int) c;
  {
    up_mask_.assign(nc, 0);
    for (const CellList *lst : {&lists_.V, &lists_.W})
      for (int a : lst->idx)
        if (tree_.top_index[a] < 0) up_mask_[a] = 1;
    for (int a : plists_.W.idx)    // periodic W entries with an image shift (else empty)
      if (opt_.periodic && tree_.top_index[a] < 0) up_mask_[a] = 1;
    for (std::size_t f = 0; f < dd.frontier.size(); ++f)
      if (dd.responsible[f]) up_mask_[local_of[dd.frontier[f]]] = 1;
    for (std::size_t c = 1; c < nc; ++c)
      if (tree_.top_index[c] < 0 && up_mask_[tree_.cells[c].parent]) up_mask_[c] = 1;
  }
  upward(tree_.depth, first_level(), false);
  // densities of the frontier cells: from the responsible rank (which holds the whole cell),
  // one sum over ranks; then M2M over the top levels on every rank
  std::vector<int> slots;    // local indices of the frontier cells with densities
  std::vector<char> mine;
  for (std::size_t f = 0; f < dd.frontier.size(); ++f) {
    const int c = local_of[dd.frontier[f]];
    if (tree_.cells[c].level >= first_level() && tree_.cells[c].gsrc > 0) {
      slots.push_back(c);
      mine.push_back(dd.responsible[f]);
    }
  }
  std::vector<double> buf(slots.size() * (std::size_t) nsurf_, 0.0);
  for (std::size_t k = 0; k < slots.size(); ++k)
    if (mine[k]) std::copy(up(slots[k]), up(slots[k]) + nsurf_, &buf[k * nsurf_]);
  const double tc = omp_get_wtime();
  comm.allreduce_sum(buf.data(), buf.size());
  const double t_reduce = omp_get_wtime() - tc;
  stats_.t_comm += t_reduce;
  for (std::size_t k = 0; k < slots.size(); ++k)
    std::copy(&buf[k * nsurf_], &buf[(k + 1) * nsurf_], up(slots[k]));
  // M2M over the top cells with children (the same on every rank)
  for (std::size_t c = 0; c < nc; ++c) {
    const int t = tree_.top_index[c];
    up_mask_[c] = t >= 0 && dd.top.cells[t].n_children > 0;
  }
  upward(dd.top.top_level - 1, first_level(), true);
  up_mask_.clear();
  const double t4 = omp_get_wtime();
  stats_.t_upward = t4 - t3 - t_reduce;
  m2l();
  const double t5 = omp_get_wtime();
  stats_.t_m2l = t5 - t4;
  p2l();
  if (opt_.periodic) {
    // own sources come first in the local source array: the background moments of this rank's
    // sources, summed over ranks
    std::size_t own_src = 0;
    for (std::size_t i = 0; i < n; ++i) own_src += q[i] != 0.0;
    periodic_far(own_src);
    const double tm = omp_get_wtime();
    comm.allreduce_sum(periodic_moments_, 5);
    stats_.t_comm += omp_get_wtime() - tm;
  }
  const double t6 = omp_get_wtime();
  stats_.t_wx = t6 - t5;
  downward();
  stats_.t_downward = omp_get_wtime() - t6;
  leaf_pass(pot != nullptr, grad != nullptr);
  if (opt_.periodic) periodic_near(pot != nullptr);
  results_to_input_order(n, pot, grad);
  // a point of nonzero strength meets itself once (not a coincident pair)
  std::size_t self = 0;
  for (std::size_t i = 0; i < n; ++i) self += q[i] != 0.0;
  if (stats_.coincident_pairs >= self) stats_.coincident_pairs -= self;
  stats_.tree_bytes = tree_.bytes() + lists_.bytes() +
      sizeof(double) * (up_equiv_.size() + dn_check_.size() + dn_equiv_.size() + xhat_.capacity() + yhat_.capacity() +
                        sx_.size() * 4 + tx_.size() * 7 + dd.xyz.capacity() + dd.q.capacity());
  finish();
}

}    // namespace kifmm
