// Cost model of one evaluation (potential + gradient, one thread, sources = targets) on n
// points spread uniformly over the root cube, as a function of the tree depth d: a full tree
// of 8^d leaves with m = n / 8^d points each. Counts (exact for the full tree, expected values
// for random points):
//   near  = mutual near-field point pairs: adjacent leaf pairs (ordered, the leaf with itself
//           included) * m^2 / 2; a leaf has 27 neighbors (itself included) with periodic
//           boundaries, (3 - 2/n_l)^3 on average in an open cube of n_l leaves per side
//   trans = M2L translations (V list entries) over the levels with expansions: open, levels
//           >= 2, pairs with adjacent parents that are not adjacent themselves; periodic, 189
//           per cell at levels >= 3, and the distinct source cells at levels 1, 2 (8 and 56
//           per cell: there the kernels of one source cell are summed over its image slots)
//   cells = cells with expansions (upward/downward passes, FFTs): levels >= 2 open, >= 0 periodic
// cost = point * n + pair * near + translation * trans + cell * cells, with per-order constants
// (seconds) fitted by `bench/calibrate --cost` to measured evaluations (calibration.cpp). The
// tree choice of kspace_style kifmm is the depth of least modelled cost (choose_tree, kifmm.h),
// realised by the leaf size leaf_size_for_depth(n, d).
#pragma once

#include <cstddef>

namespace kifmm {

struct TreeCounts {
  double near_pairs = 0, translations = 0, cells = 0;
};

// Counts of a full tree of the given depth over n uniform points (see above).
TreeCounts uniform_tree_counts(std::size_t n, int depth, bool periodic);

// Leaf size (max points per leaf) whose tree over n uniform points has depth d: with the mean
// leaf occupancy m = n / 8^d, m + 6 sqrt(m) + 3 (random occupancies do not exceed it, and cells
// of depth d - 1, 8 m points, exceed it by 6 of their standard deviations); when m is too
// small for both margins, sqrt(8) m (geometrically halfway). The smallest such threshold:
// clustered points, whose dense leaves fill up to it, then stay near the occupancy that is
// optimal for uniform ones (Plummer spheres, 1e4-1e5 points, orders 4-8: 0.80-1.23 of the CPU
// time at the per-order calibrated leaf; sqrt(8) m was worse at 1e4-3e4).
int leaf_size_for_depth(std::size_t n, int depth);

struct CostConstants {
  double point = 0, pair = 0, translation = 0, cell = 0;    // seconds each
};
CostConstants cost_constants(int order);

// Modelled CPU seconds of one evaluation with the full tree of depth d.
double modelled_cost(int order, std::size_t n, bool periodic, int depth);

}    // namespace kifmm
