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
  TopTree top;
  uint64_t global_points = 0, global_sources = 0;
  std::vector<double> xyz, q;        // this rank's points (first n_own, input order), then ghosts
  std::size_t n_own = 0;
  std::vector<int> frontier;         // top cells without children in the top tree
  std::vector<char> responsible;     // per frontier cell: this rank computes its density
  std::size_t ghost_bytes = 0;       // bytes of ghost points this rank sent
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

// Collective. n points of this rank (xyz interleaved, strengths q; every point is a target,
// the ones with q != 0 are sources). top_level 0: adaptive top tree with L = choose_top_level
// (refined where a cell holds more than 2 N / 8^L points); > 0: the top tree is the global tree
// down to that level exactly (tests). pow2_root rounds the
// root half-width up to a power of two (kernels with level-dependent operators), fixed_root
// replaces the bounding cube. nsurf: equivalent surface size (W-list direct threshold).
// periodic: fixed_root is the periodic cell (points already wrapped into it); cells are
// neighbours also through the cell's faces (images with root shifts in {-1,0,1}^3), so the
// ghost requests wrap around the boundary.
void distributed_setup(Communicator &comm, int top_level, int leaf_size, int max_depth, int nsurf, bool pow2_root,
                       const RootBox *fixed_root, bool periodic, std::size_t n, const double *xyz, const double *q,
                       DistributedData &out);

// Keep only the targets with input index < n_keep in the sorted target order (ranges remapped;
// gtrg keeps the counts the tree was split with).
void keep_targets(Octree &tree, std::size_t n_keep);

}    // namespace kifmm
