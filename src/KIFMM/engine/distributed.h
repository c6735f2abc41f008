// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Distributed evaluation, the part that does not depend on the kernel: global root and top
// tree from reductions, frontier cells, who holds what, and the import of ghost points
// (doc/design.md, "MPI: distributed evaluation"). Used by FmmEvaluator::evaluate_distributed.
#pragma once

#include "communicator.h"
#include "octree.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace kifmm {

struct DistributedData {
  RootBox root;
  // the global top tree (cells [0, n_top_global)); exchange_let appends the cells of the
  // locally essential trees this rank received below open frontier cells (LET cells)
  TopTree top;
  int n_top_global = 0;
  std::vector<char> top_internal;    // global top cells with children in the global top tree
  uint64_t global_points = 0, global_sources = 0;
  std::vector<double> xyz, q;        // this rank's points (first n_own, input order), then ghosts
  bool moments = false;              // the points carry dipole moments
  std::vector<double> mu;            // their dipole moments (3 per point when moments)
  std::size_t n_own = 0;
  std::vector<int> frontier;         // top cells without children in the top tree
  std::vector<int> frontier_index;   // per global top cell: its index in frontier, or -1
  std::vector<char> responsible;     // per frontier cell: this rank computes its density
  std::vector<char> occupied;        // per frontier cell: this rank holds own points there
  std::vector<char> complete;        // per frontier cell: all its points are here (own + imported)
  bool any_let = false;              // some rank needs a LET (exchange_let must be called)
  std::vector<std::vector<int>> let_from;    // per rank: frontier cells whose LET this rank needs from it
  std::vector<std::size_t> ghost_from;       // ghosts from rank r: points [n_own + ghost_from[r], n_own + ghost_from[r+1])
  std::vector<double> let_density;   // nsurf per LET cell (top cell n_top_global + k)
  std::vector<char> let_has_density;
  std::size_t ghost_bytes = 0;       // bytes of ghost points this rank sent (whole cells and LET)
  std::size_t let_bytes = 0;         // bytes of LET fragments this rank sent (cells, densities, points)
  std::size_t let_cells = 0;         // LET cells this rank received
  double t_comm = 0;                 // time inside communication calls
};

// Level L of the top tree (2..5, at most max_depth) for N points on P ranks: the one with the
// lowest estimated cost per rank, counted in bytes: ghost points ((N/P) ((1 + 2r)^3 - 1) with
// r = P^(1/3) / 2^L, a layer of frontier cells around a cubic domain) at 32 bytes plus
// kGhostWork for the work they cause (tree build, near-field sources; a ghost point costs
// about 0.8 of an own point's CPU, i.e. ~14 kB at 5 GB/s, see doc/scaling.md: 4 kB is a
// conservative weight), plus the frontier densities 8 nsurf min(8^L, 2N / leaf_size).
constexpr double kGhostWork = 4096.0;
int choose_top_level(uint64_t npoints, int nranks, int nsurf, int max_depth, int leaf_size);

// Coordinate bounds of the points of all ranks (one reduction): lo, hi over every rank's xyz
// (a rank without points contributes nothing; no points anywhere: lo = +max, hi = -max).
void global_bounds(Communicator &comm, std::size_t n, const double *xyz, double lo[3], double hi[3]);

// Parameters of distributed_setup (from the evaluator's options).
struct DistributedConfig {
  // 0: adaptive top tree with L = choose_top_level (refined where a cell holds more than
  // 2 N / 8^L points); > 0: the top tree is the global tree down to that level exactly (tests)
  int top_level = 0;
  int leaf_size = 1;
  int max_depth = 20;
  int nsurf = 0;                          // equivalent surface size (W-list direct threshold)
  bool pow2_root = false;                 // root half-width rounded up to a power of two
                                          // (kernels with level-dependent operators)
  const RootBox *fixed_root = nullptr;    // instead of the bounding cube
  // fixed_root is the periodic cell (points already wrapped into it); cells are neighbours also
  // through the cell's faces (images with root shifts in {-1,0,1}^3), so the ghost requests
  // wrap around the boundary
  bool periodic = false;
};

// This rank's points: n, xyz interleaved, strengths q and, for dipole evaluations (moments: the
// same on every rank), moments mu (3 per point). Every point is a target; the ones with q != 0
// or mu != 0 are sources.
struct LocalPoints {
  std::size_t n = 0;
  const double *xyz = nullptr, *q = nullptr, *mu = nullptr;
  bool moments = false;
  bool source(std::size_t i) const
  {
    return q[i] != 0.0 || (moments && (mu[3 * i] != 0.0 || mu[3 * i + 1] != 0.0 || mu[3 * i + 2] != 0.0));
  }
};

// A point in the messages of the distributed evaluation: x y z q, and mx my mz with moments.
inline std::size_t point_record_size(bool moments) { return moments ? 7 : 4; }
inline void pack_point(std::vector<double> &out, const double *xyz, const double *q, const double *mu, std::size_t i)
{
  out.insert(out.end(), {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], q[i]});
  if (mu) out.insert(out.end(), {mu[3 * i], mu[3 * i + 1], mu[3 * i + 2]});
}
// appends the point record at v to xyz, q (and mu when moments)
inline void unpack_point(const double *v, bool moments, std::vector<double> &xyz, std::vector<double> &q,
                         std::vector<double> &mu)
{
  xyz.insert(xyz.end(), v, v + 3);
  q.push_back(v[3]);
  if (moments) mu.insert(mu.end(), v + 4, v + 7);
}

// Collective: global root and counts, top tree, frontier cells, who holds what, and the import
// of the whole cells' points (ghosts).
void distributed_setup(Communicator &comm, const DistributedConfig &config, const LocalPoints &points,
                       DistributedData &out);

// Locally essential trees (after distributed_setup, collective). tree: this rank's tree over
// its own (the first n_own input points) and imported points, built with dd.top, complete
// below the frontier cells marked dd.complete; up: upward densities (nsurf per cell of tree) of
// every cell below those frontier cells. A rank asks the responsible rank of each open frontier
// cell F in dd.let_from for its LET, sending the cells of its tree that hold its own points and
// touch F (level, position, leaf or not; a frontier cell that is not complete here stands for
// the unknown cells of its own points inside it, and F itself for none: the responsible rank,
// which imported this rank's points of F, finds its cells there). The responsible rank answers
// with the part of F's subtree that the lists of those cells reach (none of the asking rank's
// own points):
//   cells: the children of every cell P that touches an asking cell of P's level that splits,
//          or an asking leaf of P's level or coarser (colleagues and V lists, the descent of
//          U/W lists), with their global counts and densities (or, for a cell of fewer than
//          nsurf / 4 points (nsurf / 7 with dipole moments), its points, which take fewer bytes);
//   points: of the leaves that touch an asking leaf or an asking cell of their level or finer
//          (U, X lists), and of the subtrees of at most nsurf sources whose parent touches a
//          coarser asking leaf (W lists, evaluated directly).
// Received fragments are appended to dd: cells to dd.top (top.open: split in the global tree,
// children not sent), densities to dd.let_density, points to dd.xyz / dd.q.
void exchange_let(Communicator &comm, const Octree &tree, std::size_t n_own, const std::vector<double> &up, int nsurf,
                  bool periodic, DistributedData &dd);

// Keep only the targets with input index < n_keep in the sorted target order (ranges remapped;
// gtrg keeps the counts the tree was split with).
void keep_targets(Octree &tree, std::size_t n_keep);

}    // namespace kifmm
