// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic evaluation on one level of k^3 cells: FmmEvaluator<K>::evaluate_grid (included at
// the end of fmm_core.h; the method is described in periodic_grid.h). Points are already
// wrapped into the cell (the fixed root). Passes: bin -> P2M -> surface FFTs -> convolution
// over the cells (all far images) -> inverse FFTs -> check-to-equivalent -> L2P; near field
// (each cell with itself and its neighbours, grid_near_depth; mutual when sources = targets);
// Laplace background term.
#pragma once

#include "fmm_core.h"
#include "periodic_grid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <type_traits>

namespace kifmm {

template <class K>
void FmmEvaluator<K>::evaluate_grid(std::size_t ns, const double *sxyz, const double *sq, std::size_t nt,
                                    const double *txyz, double *pot, double *grad, bool same_points)
{
  if constexpr (!std::is_same_v<K, LaplaceKernel> && !std::is_same_v<K, YukawaKernel>) {
    throw std::invalid_argument("kifmm: the periodic grid (Options::periodic_grid) is for the Laplace and Yukawa kernels");
  } else {
    const double t0 = omp_get_wtime();
    grid_bin(ns, sxyz, sq, nt, txyz, same_points, ns);
    stats_.t_tree = omp_get_wtime() - t0;
    grid_passes(nullptr, ns, pot != nullptr, same_points);
    results_to_input_order(nt, pot, grad);
  }
}

// Distributed (evaluate_distributed with Options::periodic_grid): every rank bins its own
// points; the near field needs the sources of the neighbour cells of every cell holding
// own targets: the ranks' target cells are all-gathered (cell indices) and each rank sends the
// others its sources in the cells next to theirs (ghosts, one alltoallv). The cells' upward
// densities are the sum of every rank's own-source part (one allreduce of k^3 surfaces), the
// convolution is done on every rank, the near field one-sided (sources include the ghosts),
// the background moments and the wrap-correction marginals are summed over ranks.
template <class K>
void FmmEvaluator<K>::evaluate_grid_distributed(Communicator &comm, const LocalPoints &pts, double *pot,
                                                double *grad, double *hess)
{
  const std::size_t n = pts.n;
  const double *xyz = pts.xyz;
  if constexpr (!std::is_same_v<K, LaplaceKernel> && !std::is_same_v<K, YukawaKernel>) {
    throw std::invalid_argument("kifmm: the periodic grid (Options::periodic_grid) is for the Laplace and Yukawa kernels");
  } else {
    const double t0 = omp_get_wtime();
    const GridGeometry g = grid_geometry();
    const int kc = g.kc;
    // own targets' cells, all-gathered
    std::vector<char> mine(kc, 0);
    for (std::size_t i = 0; i < n; ++i) mine[grid_cell_of(xyz + 3 * i)] = 1;
    std::vector<int> my_cells, all_cells, counts;
    for (int b = 0; b < kc; ++b)
      if (mine[b]) my_cells.push_back(b);
    double tc = omp_get_wtime();
    comm.allgatherv(my_cells, all_cells, counts);
    stats_.t_comm += omp_get_wtime() - tc;
    // own sources (q != 0 or mu != 0) first, then the ghosts
    const bool moments = pts.moments;
    std::vector<double> sxyz, sq, smu;
    for (std::size_t i = 0; i < n; ++i)
      if (pts.source(i)) {
        sxyz.insert(sxyz.end(), xyz + 3 * i, xyz + 3 * i + 3);
        sq.push_back(pts.q[i]);
        if (moments) smu.insert(smu.end(), pts.mu + 3 * i, pts.mu + 3 * i + 3);
      }
    const std::size_t own = sq.size();
    std::vector<int> own_cell(own);
    for (std::size_t j = 0; j < own; ++j) own_cell[j] = grid_cell_of(&sxyz[3 * j]);
    const int nr = comm.size(), me = comm.rank();
    std::vector<std::vector<double>> send(nr), recv;
    std::vector<char> near(kc);
    const auto offsets = grid_near_offsets(g.m);
    for (int r = 0, at = 0; r < nr; at += counts[r], ++r) {
      if (r == me) continue;
      std::fill(near.begin(), near.end(), 0);
      for (int e = at; e < at + counts[r]; ++e)
        for (const auto &o : offsets) {
          signed char sh[3];
          const int a = grid_neighbour(all_cells[e], o[0], o[1], o[2], sh);
          if (a >= 0) near[a] = 1;
        }
      for (std::size_t j = 0; j < own; ++j)
        if (near[own_cell[j]]) pack_point(send[r], sxyz.data(), sq.data(), moments ? smu.data() : nullptr, j);
    }
    tc = omp_get_wtime();
    comm.alltoallv(send, recv);
    stats_.t_comm += omp_get_wtime() - tc;
    const std::size_t w = point_record_size(moments);
    for (const auto &v : recv)
      for (std::size_t j = 0; j + w <= v.size(); j += w) unpack_point(&v[j], moments, sxyz, sq, smu);
    stats_.n_ghosts = sq.size() - own;
    for (const auto &v : send) stats_.ghost_bytes += v.size() * sizeof(double);
    std::size_t global = own;
    {
      uint64_t g = own;
      comm.allreduce_sum(&g, 1);
      global = g;
    }
    stats_.n_sources = global;
    if (global == 0) {
      stats_.comm_bytes = comm.bytes_sent();
      return;
    }
    if (moments) dip_mu_ = smu.empty() ? kMomentsElsewhere : smu.data();    // input order of sxyz (grid_bin)
    grid_bin(sq.size(), sxyz.data(), sq.data(), n, xyz, false, own);
    stats_.t_tree = omp_get_wtime() - t0 - stats_.t_comm;
    grid_passes(&comm, own, pot != nullptr, false);
    results_to_input_order(n, pot, grad, hess);
    // a point of nonzero strength meets itself once (not a coincident pair)
    if (stats_.coincident_pairs >= own) stats_.coincident_pairs -= own;
    stats_.comm_bytes = comm.bytes_sent();
  }
}

template <class K> int FmmEvaluator<K>::grid_cell_of(const double *x) const
{
  int cells[3];
  grid_cells_per_axis(opt_.periodic_grid, opt_.root_shape, cells);
  return grid_cell_index(x, opt_.root_center, opt_.root_half_width, opt_.root_shape, cells);
}

// The neighbour cell, -1 where there is none (a slab: beyond its faces in z)
template <class K> int FmmEvaluator<K>::grid_neighbour(int b, int dx, int dy, int dz, signed char sh[3]) const
{
  int cells[3];
  const bool slab = opt_.periodic_dims == 2;
  grid_cells_per_axis(opt_.periodic_grid, opt_.root_shape, cells);
  const int c = grid_neighbour_cell(b, cells, dx, dy, dz, sh);
  return slab && sh[2] != 0 ? -1 : c;
}

// Points sorted by cell (stable counting sort: within a cell the input order, so the own
// sources, input indices below own_sources, are a prefix of every cell's range), sorted copies.
template <class K>
void FmmEvaluator<K>::grid_bin(std::size_t ns, const double *sxyz, const double *sq, std::size_t nt,
                               const double *txyz, bool same_points, std::size_t own_sources)
{
  const GridGeometry g = grid_geometry();
  const int kc = g.kc;
  tree_ = Octree{};
  for (int d = 0; d < 3; ++d) {
    tree_.root.center[d] = opt_.root_center[d];
    tree_.root.shape[d] = opt_.root_shape[d];
  }
  tree_.root.half_width = opt_.root_half_width;
  auto bin = [&](std::size_t n, const double *xyz, std::vector<int> &begin, std::vector<uint32_t> &order) {
    std::vector<int> cell(n);
    begin.assign(kc + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++begin[(cell[i] = grid_cell_of(xyz + 3 * i)) + 1];
    for (int b = 0; b < kc; ++b) begin[b + 1] += begin[b];
    std::vector<int> next(begin.begin(), begin.end() - 1);
    order.resize(n);
    for (std::size_t i = 0; i < n; ++i) order[next[cell[i]]++] = (uint32_t) i;
  };
  bin(ns, sxyz, grid_src_begin_, tree_.src_order);
  if (same_points) {
    grid_trg_begin_ = grid_src_begin_;
    tree_.trg_order = tree_.src_order;
  } else {
    bin(nt, txyz, grid_trg_begin_, tree_.trg_order);
  }
  grid_own_end_.resize(kc);
  for (int b = 0; b < kc; ++b) {
    int e = grid_src_begin_[b];
    while (e < grid_src_begin_[b + 1] && tree_.src_order[e] < own_sources) ++e;
    grid_own_end_[b] = e;
  }
  sorted_copies(ns, sxyz, sq, nt, txyz);
}

template <class K> typename FmmEvaluator<K>::GridGeometry FmmEvaluator<K>::grid_geometry() const
{
  GridGeometry g;
  if (opt_.periodic_grid < 3) throw std::invalid_argument("kifmm: Options::periodic_grid needs at least 3 cells per side");
  g.slab = opt_.periodic_dims == 2;
  grid_cells_per_axis(opt_.periodic_grid, opt_.root_shape, g.k);
  g.kc = g.k[0] * g.k[1] * g.k[2];
  g.H = opt_.root_half_width;
  g.h = g.H * grid_cell_shape(g.k, opt_.root_shape, g.cs);
  grid_near_depth(g.cs, g.m, g.ss);
  for (int d = 0; d < 3; ++d) {
    g.L[d] = 2.0 * g.H * opt_.root_shape[d];
    g.w[d] = g.L[d] / g.k[d];
  }
  return g;
}

// Laplace, or Yukawa with kappa * H: the kernel of the unit periodic cell (largest half-width 1)
// whose lattice sums the grid's kernel tables hold
template <class K> KernelSpec FmmEvaluator<K>::grid_unit_kernel(const GridGeometry &g) const
{
  if constexpr (std::is_same_v<K, YukawaKernel>) return KernelSpec{KernelType::Yukawa, k_.kappa * g.H};
  (void) g;
  return KernelSpec{};
}

template <class K> void FmmEvaluator<K>::grid_center(const GridGeometry &g, int b, double ctr[3]) const
{
  const int a[3] = {b / (g.k[1] * g.k[2]), (b / g.k[2]) % g.k[1], b % g.k[2]};
  for (int d = 0; d < 3; ++d) ctr[d] = opt_.root_center[d] - 0.5 * g.L[d] + (a[d] + 0.5) * g.w[d];
}

template <class K> void FmmEvaluator<K>::grid_reduce(Communicator *comm, double *v, std::size_t m)
{
  if (!comm) return;
  const double tc = omp_get_wtime();
  comm->allreduce_sum(v, m);
  stats_.t_comm += omp_get_wtime() - tc;
}

// The passes after binning (comm: null on one process; distributed: the upward densities,
// cell occupancies, background moments and wrap marginals are summed over ranks).
template <class K>
void FmmEvaluator<K>::grid_passes(Communicator *comm, std::size_t own_sources, bool want_pot, bool same_points)
{
  if constexpr (std::is_same_v<K, LaplaceKernel> || std::is_same_v<K, YukawaKernel>) {
    const GridGeometry g = grid_geometry();
    const std::size_t nt = tx_.size();
    stats_.depth = 0;
    stats_.n_cells = stats_.n_leaves = g.kc;
    grid_operators(g);
    up_equiv_.assign((std::size_t) g.kc * nsurf_, 0.0);
    dn_check_.assign((std::size_t) g.kc * nsurf_, 0.0);
    dn_equiv_.assign((std::size_t) g.kc * nsurf_, 0.0);
    tp_.assign(nt, 0.0);
    tgx_.assign(nt, 0.0);
    tgy_.assign(nt, 0.0);
    tgz_.assign(nt, 0.0);
    for (auto &h : th_) h.assign(hess_ ? nt : 0, 0.0);
    const double t2 = omp_get_wtime();
    grid_p2m(g);
    // cells with sources on any rank; the densities of the whole cells
    std::vector<double> occupied(g.kc);
    for (int b = 0; b < g.kc; ++b) occupied[b] = grid_own_end_[b] - grid_src_begin_[b];
    grid_reduce(comm, occupied.data(), g.kc);
    grid_reduce(comm, up_equiv_.data(), up_equiv_.size());
    const double t3 = omp_get_wtime();
    stats_.t_upward = t3 - t2;
    grid_m2l(g, occupied, *grid_kernel_, scale_[0]);
    const double t4 = omp_get_wtime();
    stats_.t_m2l = t4 - t3;
    grid_l2p(g, want_pot);
    const double t5 = omp_get_wtime();
    stats_.t_downward = t5 - t4;
    stats_.coincident_pairs = same_points ? grid_near_mutual(g, want_pot) : grid_near_one_sided(g, want_pot);
    stats_.t_p2p = omp_get_wtime() - t5;
    // ---- Laplace background (non-harmonic part of G_per), exact from the moments
    const double quad = grid_kernel_->quad / (g.h * g.h * g.h);
    periodic_background_moments(quad, opt_.root_center, own_sources);
    grid_reduce(comm, periodic_moments_, 5);
    add_periodic_background(want_pot, opt_.root_center);
    if (quad != 0.0) grid_wrap_correction(g, comm, quad, want_pot);    // Laplace (Yukawa has no background)
    stats_.tree_bytes = grid_spectra_.bytes() + sizeof(double) * (up_equiv_.size() + dn_check_.size() + dn_equiv_.size() +
                                                                  sx_.size() * 4 + tx_.size() * 7);
  } else {
    (void) comm;
    (void) own_sources;
    (void) want_pot;
    (void) same_points;
  }
}

// operators of the cell size, and the grid kernels
template <class K> void FmmEvaluator<K>::grid_operators(const GridGeometry &g)
{
  double t_setup = 0, s = 1.0;
  // surfaces of the grid's shape (nearly cubic cells: the cell's, in memory only; cubes and
  // stretched cells: cubic)
  const UnitKernel uk = make_unit_kernel(k_, g.h, s, g.ss);
  ops_.assign(1, get_operator_set(uk, p_, uk.cubic() ? opt_.cache_dir : std::string(), &t_setup));
  RootBox cell;
  for (int d = 0; d < 3; ++d) cell.shape[d] = g.ss[d];
  shape_surfaces(cell);
  scale_.assign(1, s);
  if (!fft_ || fft_->p() != p_) fft_ = std::make_unique<M2LTransform>(p_);
  const double tg = omp_get_wtime();
  grid_kernel_ = periodic_grid_kernel(grid_unit_kernel(g), g.k, p_, g.cs, g.slab);
  stats_.t_precompute = t_setup + (omp_get_wtime() - tg);
  stats_.operator_bytes = ops_[0]->bytes() + grid_kernel_->bytes();
}

// The cells with range [begin[b], end[b]) not empty, in index order: the cells whose operators
// are applied (own sources: P2M; own targets: L2P). On several ranks a rank holds the points of
// a part of the cells, and heaped points leave most cells empty: the batched operators go over
// these cells only (on one process with every cell occupied, all cells in the same batches).
inline std::vector<int> grid_busy_cells(const std::vector<int> &begin, const int *end, int kc)
{
  std::vector<int> cells;
  for (int b = 0; b < kc; ++b)
    if (end[b] > begin[b]) cells.push_back(b);
  return cells;
}

// P2M of the cells' own sources, batched over the cells holding some
template <class K> void FmmEvaluator<K>::grid_p2m(const GridGeometry &g)
{
  const std::vector<int> &sb = grid_src_begin_, &own_end = grid_own_end_;
  const OperatorSet &op = *ops_[0];
  const double s = scale_[0];
  const std::vector<int> cells = grid_busy_cells(sb, own_end.data(), g.kc);
  const int nb = (int) cells.size(), nchunks = (nb + kGridBatch - 1) / kGridBatch;
#pragma omp parallel
  {
    SurfacePoints surf;
    std::vector<double> chk, eq;
#pragma omp for schedule(dynamic, 1)
    for (int ch = 0; ch < nchunks; ++ch) {
      const int j0 = ch * kGridBatch, m = std::min(nb, j0 + kGridBatch) - j0;
      chk.assign((std::size_t) nsurf_ * m, 0.0);
      for (int j = 0; j < m; ++j) {
        const int b = cells[j0 + j];
        double ctr[3];
        grid_center(g, b, ctr);
        box_surface(outer_, ctr, g.h, surf);
        p2p<K, true, false, false>(k_, surface_span(surf, nullptr), source_range(sb[b], own_end[b] - sb[b]),
                                   {&chk[(std::size_t) j * nsurf_]});
      }
      eq.resize(chk.size());
      apply_pinv_batch(op.uc2e_a, op.uc2e_b, nsurf_, op.rank, chk.data(), m, eq.data(), 1.0 / s);
      for (int j = 0; j < m; ++j)
        std::copy(&eq[(std::size_t) j * nsurf_], &eq[(std::size_t) (j + 1) * nsurf_], up(cells[j0 + j]));
    }
  }
}

// M2L: surface spectra of all cells -> convolution over the cells with gk -> check potentials
// (added to the downward check values, times s: the kernel's scale at the cell size)
template <class K>
void FmmEvaluator<K>::grid_m2l(const GridGeometry &g, const std::vector<double> &occupied, const GridKernel &gk,
                              double s)
{
  const std::vector<int> &tb = grid_trg_begin_;
  const int nf = gk.nfreq, kc = g.kc;
  std::complex<double> *z = grid_spectra_.get((std::size_t) nf * gk.slots());
  if (gk.slots() != (std::size_t) kc)    // a slab's zero padding along z
    std::fill(z, z + (std::size_t) nf * gk.slots(), std::complex<double>(0.0));
  // the frequency blocks that hold data (the last block of a row, grid_row_stride's padding, is
  // neither written nor read)
  const int nused = fft_->nfreq(), nblk = nused / 16;
#pragma omp parallel
  {
    M2LTransform::Workspace ws(*fft_);
    std::vector<double> chunk((std::size_t) nblk * 32);
#pragma omp for schedule(static)
    for (int b = 0; b < kc; ++b) {
      std::complex<double> *zb = z + gk.slot(b) * nf;
      if (occupied[b] == 0) {
        std::fill(zb, zb + nused, std::complex<double>(0.0));
        continue;
      }
      fft_->forward(up(b), chunk.data(), 32, ws);
      for (int f = 0; f < nused; ++f)
        zb[f] = std::complex<double>(chunk[(f / 16) * 32 + f % 16], chunk[(f / 16) * 32 + 16 + f % 16]);
    }
#pragma omp for schedule(dynamic, 1)
    for (int blk = 0; blk < nblk; ++blk) grid_convolve(gk, z, 16 * blk, 16 * blk + 16);
#pragma omp for schedule(static)
    for (int b = 0; b < kc; ++b) {
      if (tb[b + 1] == tb[b]) continue;
      for (int f = 0; f < nused; ++f) {
        const std::complex<double> v = z[gk.slot(b) * nf + f];
        chunk[(f / 16) * 32 + f % 16] = v.real();
        chunk[(f / 16) * 32 + 16 + f % 16] = v.imag();
      }
      fft_->inverse_add(chunk.data(), 32, dcheck(b), s, ws);
    }
  }
}

// check -> downward equivalent (batched over the cells holding own targets), L2P
template <class K> void FmmEvaluator<K>::grid_l2p(const GridGeometry &g, bool want_pot)
{
  const std::vector<int> &tb = grid_trg_begin_;
  const OperatorSet &op = *ops_[0];
  const double s = scale_[0];
  const std::vector<int> cells = grid_busy_cells(tb, tb.data() + 1, g.kc);
  const int nb = (int) cells.size(), nchunks = (nb + kGridBatch - 1) / kGridBatch;
#pragma omp parallel
  {
    SurfacePoints surf;
    std::vector<double> chk, eq;
#pragma omp for schedule(dynamic, 1)
    for (int ch = 0; ch < nchunks; ++ch) {
      const int j0 = ch * kGridBatch, m = std::min(nb, j0 + kGridBatch) - j0;
      chk.resize((std::size_t) nsurf_ * m);
      for (int j = 0; j < m; ++j) std::copy(dcheck(cells[j0 + j]), dcheck(cells[j0 + j]) + nsurf_, &chk[(std::size_t) j * nsurf_]);
      eq.resize(chk.size());
      apply_pinv_batch(op.dc2e_a, op.dc2e_b, nsurf_, op.rank, chk.data(), m, eq.data(), 1.0 / s);
      for (int j = 0; j < m; ++j) {
        const int b = cells[j0 + j];
        std::copy(&eq[(std::size_t) j * nsurf_], &eq[(std::size_t) (j + 1) * nsurf_], dequiv(b));
        double ctr[3];
        grid_center(g, b, ctr);
        box_surface(outer_, ctr, g.h, surf);
        p2p_pg<K, false>(k_, want_pot, target_range(tb[b], tb[b + 1] - tb[b]), surface_span(surf, dequiv(b)),
                         result_at(tb[b]));
      }
    }
  }
}

// The work of the mutual near field (grid_near_mutual): the nonempty cells (self tasks); per
// cell, its nonempty neighbours at the second half of the offsets (grid_near_offsets), one
// pair per neighbour cell with the displacements of every shift it is met at (d[3 s .. 3 s + 2]
// for s in [first[e], first[e + 1]) of pair e); the cell's own images among those offsets (the
// same for every cell). neighbour(b, dx, dy, dz, sh): FmmEvaluator::grid_neighbour.
struct GridMutualPlan {
  std::vector<int> self;
  std::vector<MutualPair> pairs;
  std::vector<int> first{0};
  std::vector<double> d;
  std::vector<std::array<signed char, 3>> self_images;
};
template <class Neighbour>
GridMutualPlan grid_mutual_plan(int kc, const std::vector<int> &sb, const int m[3], const double L[3], Neighbour neighbour)
{
  GridMutualPlan plan;
  const auto all = grid_near_offsets(m);
  const std::vector<std::array<int, 3>> half(all.begin() + all.size() / 2 + 1, all.end());
  for (const auto &o : half) {
    signed char sh[3];
    if (neighbour(0, o[0], o[1], o[2], sh) == 0) plan.self_images.push_back({sh[0], sh[1], sh[2]});
  }
  std::vector<MutualPair> met;    // one cell's neighbours at their shifts
  for (int b = 0; b < kc; ++b) {
    if (sb[b + 1] == sb[b]) continue;
    plan.self.push_back(b);
    met.clear();
    for (const auto &o : half) {
      MutualPair pr;
      pr.a = b;
      pr.b = neighbour(b, o[0], o[1], o[2], pr.shift);
      if (pr.b >= 0 && pr.b != b && sb[pr.b + 1] > sb[pr.b]) met.push_back(pr);
    }
    for (std::size_t i = 0; i < met.size(); ++i) {
      bool seen = false;
      for (std::size_t j = 0; j < i && !seen; ++j) seen = met[j].b == met[i].b;
      if (seen) continue;
      plan.pairs.push_back(met[i]);
      for (std::size_t j = i; j < met.size(); ++j)
        if (met[j].b == met[i].b)
          for (int c = 0; c < 3; ++c) plan.d.push_back(met[j].shift[c] * L[c]);
      plan.first.push_back((int) (plan.d.size() / 3));
    }
  }
  return plan;
}

// Near field, sources = targets: each cell with itself and its neighbours (offsets within
// g.m per axis, images included), pair by pair for both cells (grid_mutual_plan). With few
// cells along an axis one neighbour cell is met at several shifts (one pair, all its shifts in
// one pass); with offsets a multiple of the cells along every axis, the cell's neighbours
// include its own images: those go with the cell's self task, one-sided at +shift and -shift
// (the pair evaluation would write both sides of one cell at once). Returns the coincident
// pairs.
template <class K> std::size_t FmmEvaluator<K>::grid_near_mutual(const GridGeometry &g, bool want_pot)
{
  const std::vector<int> &sb = grid_src_begin_;
  const GridMutualPlan plan = grid_mutual_plan(
      g.kc, sb, g.m, g.L, [&](int b, int dx, int dy, int dz, signed char *sh) { return grid_neighbour(b, dx, dy, dz, sh); });
  stats_.mutual_pairs = plan.pairs.size();
  return run_mutual_tasks(g.kc, plan.self, plan.pairs, [&](int a, int b, const signed char *, bool self_pair, int e) {
    const MutualSpan sa{source_range(sb[a], sb[a + 1] - sb[a]), result_at(sb[a])},
        sbb{source_range(sb[b], sb[b + 1] - sb[b]), result_at(sb[b])};
    std::size_t z0 = 0;
    if (!self_pair) {
      const double *de = &plan.d[3 * (std::size_t) plan.first[e]];
      const int nsh = plan.first[e + 1] - plan.first[e];
      if (want_pot) p2p_mutual_shifts<K, true>(k_, sa, sbb, de, nsh, &z0);
      else p2p_mutual_shifts<K, false>(k_, sa, sbb, de, nsh, &z0);
      return z0;
    }
    const double d0[3] = {0, 0, 0};
    if (want_pot) p2p_mutual<K, true>(k_, true, sa, sbb, d0, &z0);
    else p2p_mutual<K, false>(k_, true, sa, sbb, d0, &z0);
    const std::size_t t = sb[a], n = sb[a + 1] - sb[a];
    std::vector<double> x, y, z;
    for (const auto &img : plan.self_images)
      for (int sign : {1, -1}) {
        const signed char s2[3] = {(signed char) (sign * img[0]), (signed char) (sign * img[1]),
                                   (signed char) (sign * img[2])};
        grid_shifted_targets(g, t, n, s2, x, y, z);
        p2p_pg<K, true>(k_, want_pot, {n, x.data(), y.data(), z.data()}, source_range(t, n), result_at(t), &z0);
      }
    return z0;
  });
}

// Near field, one-sided: targets moved by -shift L see the sources of the image at +shift L.
// Returns the coincident pairs.
template <class K> std::size_t FmmEvaluator<K>::grid_near_one_sided(const GridGeometry &g, bool want_pot)
{
  const std::vector<int> &sb = grid_src_begin_, &tb = grid_trg_begin_;
  std::vector<std::size_t> zc(g.kc, 0);
  const auto offsets = grid_near_offsets(g.m);
#pragma omp parallel
  {
    std::vector<double> x, y, zz;
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < g.kc; ++b) {
      const std::size_t t = tb[b], n = tb[b + 1] - tb[b];
      if (n == 0) continue;
      for (const auto &o : offsets) {
        signed char sh[3];
        const int a = grid_neighbour(b, o[0], o[1], o[2], sh);
        if (a < 0) continue;
        grid_shifted_targets(g, t, n, sh, x, y, zz);
        p2p_pg<K, true>(k_, want_pot, {n, x.data(), y.data(), zz.data()}, source_range(sb[a], sb[a + 1] - sb[a]),
                        result_at(t), &zc[b]);
      }
    }
  }
  std::size_t zeros = 0;
  for (std::size_t v : zc) zeros += v;
  return zeros;
}

// Laplace: the kernels subtract quad |r|^2 at the separation r of the class representative
// (the image of the source cell nearest to the target cell, r = x - y + L m with m in
// {-1,0,1}^3 per cell pair), the moments add it back at x - y: add the difference
// quad (2 L m.(x - y) + L^2 |m|^2) = quad (2 L (alpha.x - beta) + L^2 gamma) with, per target
// cell, alpha_d = sum_s m_d Q_s, beta = sum_s m.P_s, gamma = sum_s |m|^2 Q_s (Q_s, P_s: charge
// and dipole of source cell s). m_d depends on the cells' indices along axis d only: the sums
// are over the per-axis marginals of Q and P (O(k^2) per axis).
template <class K>
void FmmEvaluator<K>::grid_wrap_correction(const GridGeometry &g, Communicator *comm, double quad, bool want_pot)
{
  const std::vector<int> &sb = grid_src_begin_, &tb = grid_trg_begin_, &own_end = grid_own_end_;
  const int *k = g.k, kc = g.kc;
  const int off[3] = {0, k[0], k[0] + k[1]}, nk = k[0] + k[1] + k[2];    // per-axis marginals, concatenated
  const double *L = g.L, *c = opt_.root_center;
  auto axis_index = [&](int b, int a[3]) {
    a[0] = b / (k[1] * k[2]);
    a[1] = (b / k[2]) % k[1];
    a[2] = b % k[2];
  };
  std::vector<double> Qa(nk, 0.0), Pa(nk, 0.0);
  for (int b = 0; b < kc; ++b) {
    int sa[3];
    axis_index(b, sa);
    for (int j = sb[b]; j < own_end[b]; ++j) {
      const double y[3] = {sx_[j] - c[0], sy_[j] - c[1], sz_[j] - c[2]};
      for (int d = 0; d < 3; ++d) {
        Qa[off[d] + sa[d]] += sq_[j];
        Pa[off[d] + sa[d]] += sq_[j] * y[d];
      }
      if (dip_mu_) {    // a dipole's part of its cell's dipole moment
        const double mu[3] = {smx_[j], smy_[j], smz_[j]};
        for (int d = 0; d < 3; ++d) Pa[off[d] + sa[d]] += mu[d];
      }
    }
  }
  grid_reduce(comm, Qa.data(), Qa.size());
  grid_reduce(comm, Pa.data(), Pa.size());
  // per axis, in units of that axis' period: A = sum m Q, B = sum m L P, C = sum m^2 L^2 Q
  std::vector<double> A(nk, 0.0), B(nk, 0.0), C(nk, 0.0);
  for (int d = 0; d < 3; ++d)
    for (int t = 0; t < k[d]; ++t)
      for (int s2 = 0; s2 < k[d]; ++s2) {
        const int m = (grid_class_representative(t - s2, k[d]) - (t - s2)) / k[d];
        A[off[d] + t] += m * L[d] * Qa[off[d] + s2];
        B[off[d] + t] += m * L[d] * Pa[off[d] + s2];
        C[off[d] + t] += m * m * L[d] * L[d] * Qa[off[d] + s2];
      }
#pragma omp parallel for schedule(static)
  for (int t = 0; t < kc; ++t) {
    int ta[3];
    axis_index(t, ta);
    const double alpha[3] = {A[off[0] + ta[0]], A[off[1] + ta[1]], A[off[2] + ta[2]]};
    const double beta = B[off[0] + ta[0]] + B[off[1] + ta[1]] + B[off[2] + ta[2]];
    const double gamma = C[off[0] + ta[0]] + C[off[1] + ta[1]] + C[off[2] + ta[2]];
    const double g2 = 2 * quad;    // gradient: g2 alpha (fused multiply-add into the accumulators)
    for (int i = tb[t]; i < tb[t + 1]; ++i) {
      const double x[3] = {tx_[i] - c[0], ty_[i] - c[1], tz_[i] - c[2]};
      if (want_pot) tp_[i] += quad * (2 * (alpha[0] * x[0] + alpha[1] * x[1] + alpha[2] * x[2] - beta) + gamma);
      tgx_[i] = std::fma(g2, alpha[0], tgx_[i]);
      tgy_[i] = std::fma(g2, alpha[1], tgy_[i]);
      tgz_[i] = std::fma(g2, alpha[2], tgz_[i]);
    }
  }
}

}    // namespace kifmm
