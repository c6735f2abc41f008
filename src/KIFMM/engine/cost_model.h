// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
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
//   self  = the part of near made of pairs inside one leaf (m^2 / 2 per leaf)
//   entries = unordered pairs of adjacent leaves (each leaf with itself included) and W, X list
//           entries: the per-pair overhead of the near field (one task per leaf pair) and lists
//   spilled = the translations of levels whose cells' frequency blocks exceed the per-core
//           cache (m2l_cached_cells), weighted by log2 of the excess: their spectra come from
//           the shared cache or memory, the more often the larger the level
//   periodic, periodic_cells = 1 and cells with periodic boundaries (0 open): the fixed cost of
//           a periodic evaluation and the extra cost of a periodic cell (their top levels sum
//           the images; without them the model underestimates periodic trees by 20-25 % at
//           orders 9-14)
// cost = point * n + pair * (near + self_extra * self) + translation * trans + cell * cells
//        + entry * entries + spill * spilled + periodic * 1 + periodic_cell * cells,
// with per-order constants (seconds) fitted by `bench/calibrate --cost` to measured evaluations
// (calibration.cpp). self_extra: a leaf with itself runs the one-sided loop over all m^2
// ordered pairs (p2p_mutual.h, AVX-512), not m^2 / 2 mutual ones; it decides depth 0 against
// depth 1 for small N (open: both are the same direct sum, measured 1.25-1.44x slower at depth
// 0 for 1e3 atoms by bench/solvers). The uniform tree choice (choose_tree(order, n,
// periodic)) is the depth of least modelled cost, realised by the leaf size
// leaf_size_for_depth(n, d).
//
// Actual trees (tree_counts): the same counts taken from the interaction lists of a tree built
// over the real points (adaptive: W and X lists too), so that the choice for clustered points
// (choose_tree(kernel, options, n, xyz), kifmm.h) compares the trees the points really give.
#pragma once

#include "kifmm.h"

#include <cstddef>

namespace kifmm {

struct Octree;
struct InteractionLists;
struct PeriodicImageLists;

struct TreeCounts {
  double near_pairs = 0, translations = 0, cells = 0;
  double self_pairs = 0;    // part of near_pairs: pairs inside one leaf
  double entries = 0;       // near-field leaf pairs (a leaf with itself included) + W + X entries
  // translations at levels with more cells than m2l_cached_cells(), whose frequency blocks do
  // not stay in the per-core cache (m2l_parent_pairs streams them once per colleague slot),
  // each weighted by log2(cells of the level / m2l_cached_cells())
  double spilled_translations = 0;
  double occupied_cells = 0;    // periodic grid: cells holding points (P2M, surface FFTs, L2P)
  // periodic octree: 1 (the fixed cost of an evaluation: the lattice operators of the top
  // levels), and its cells again (a periodic cell costs more than an open one)
  double periodic = 0, periodic_cells = 0;
};

// Cells of one level whose 16-frequency blocks (source and target: 512 bytes per cell) fit in
// the per-core (L2) cache of this machine (sysconf; 1 MiB when unknown).
double m2l_cached_cells();

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
  double point = 0, pair = 0, translation = 0, cell = 0, entry = 0, spill = 0;    // seconds each
  double periodic = 0, periodic_cell = 0;                                         // seconds each
};
CostConstants cost_constants(int order);

// Modelled CPU seconds of one evaluation with the full tree of depth d.
double modelled_cost(int order, std::size_t n, bool periodic, int depth, double pair_weight = 1.0);

// Modelled CPU seconds of one evaluation of n points with these counts.
double modelled_cost(int order, std::size_t n, const TreeCounts &counts, double pair_weight = 1.0);

// Counts of an actual tree over points that are both sources and targets (N-body), from its
// interaction lists (images: the periodic image lists, nullptr with open boundaries), at order
// p (surface points nsurf = surface_size(p) decide direct versus expansion work like the
// evaluator: fmm_core.h). On a full tree over uniform points they equal uniform_tree_counts up
// to the random leaf occupancies (unittest/engine/test_tree_choice.cpp). Adaptive trees add
// the W and X lists: one-sided kernel evaluations (M2P, P2L, direct W/X entries; the open
// mutual plan evaluates small-leaf W/X entries once for both sides, counted as pairs) are
// counted as pairs with the weight one_sided_weight().
TreeCounts tree_counts(const Octree &tree, const InteractionLists &lists, const PeriodicImageLists *images, int order);
double one_sided_weight();
double self_pair_extra();

// Counts of the actual tree that an N-body evaluation with these options and leaf size builds
// over these points (root, periodic wrapping as in evaluate()); depth: of that tree.
TreeCounts actual_tree_counts(const KernelSpec &kernel, const Options &options, std::size_t n, const double *xyz,
                              int leaf_size, int *depth = nullptr);

// Periodic single-level grid of k^3 cells (periodic_grid.h, Laplace): near = every cell with
// itself and its 26 neighbours (mutual), self = pairs inside one cell, entries = 14 per cell,
// cells = k^3 (its share of the convolution over the cells), occupied_cells = the cells holding
// points (only they run P2M, the two surface FFTs and L2P; expected (1 - e^-m) k^3 for m uniform
// points per cell), translations = 0. cost = point * n + pair * (near + (self_extra + grid self)
// * self) + entry * entries + grid cell * cells log2(cells) (the FFTs over the cells) + grid
// occupied * occupied_cells + grid point * n: the octree's constants and four per-order
// constants of the grid (GridCostConstants, fitted
// by `bench/calibrate --grid-cost`; a dense cell with itself costs about 1.25-1.45 times
// the octree's self-pair weight).
// shape: a rectangular periodic cell (grid_cells_per_axis; null: a cube); open_z: a slab (as in
// grid_counts below).
TreeCounts uniform_grid_counts(std::size_t n, int k, const double *shape = nullptr, bool open_z = false);
// The same for points wrapped into the cell [center - h, center + h)^3 (actual occupancies).
// open_z: a slab (periodic in x and y only: no neighbours across the z faces, the convolution
// over twice the cells).
TreeCounts grid_counts(std::size_t n, const double *xyz, const double center[3], double half_width, int k,
                       const double *shape = nullptr, bool open_z = false);
struct GridCostConstants {
  double cell = 0, occupied = 0, point = 0;    // seconds each
  double self = 0;    // a pair inside one cell costs (1 + self_pair_extra() + self) pairs
  double forward = 0;    // seconds: the forward surface transform of one cell, a part of `occupied`
};
GridCostConstants grid_cost_constants(int order);
double grid_convolution_cells(double cells);    // cells log2(cells): the cell term's count
// Cells of a grid as the model counts them: kd[0] kd[1] kd[2] (open_z: twice, the convolution
// is zero-padded along z), times grid_length_factor: kGridPrimeLengthFactor when a length of
// the DFT over the cells has a prime factor above 13 (FFTW has straight-line codelets up to 13;
// longer prime factors take its slower general algorithms: at order 8, 23 x 3 x 3 cells cost
// 1.2x as much per cell as 24 x 3 x 3, bench/results/periodic_grid_dft_lengths.md), else 1.
// The occupied cells are counted with the same factor: at orders 3-4 the fit puts the whole
// per-cell work on them.
constexpr double kGridPrimeLengthFactor = 1.25;
double grid_length_factor(const int kd[3], bool open_z);
double grid_modelled_cells(const int kd[3], bool open_z);
// share: evaluate_distributed with at most this share of the points on one rank, every rank
// doing the whole convolution over the cells and the forward surface transforms of all
// occupied cells (the cell term and the transforms counted 1 / share times: the slowest rank's
// time over its share; Options::model_share)
double modelled_grid_cost(int order, std::size_t n, const TreeCounts &counts, double pair_weight = 1.0,
                          double share = 1.0);
// Largest grid (cells per side) offered at this order: its kernels (periodic_grid.h) and the
// convolution buffer are each at most 64 MB (counted without the padding of grid_row_stride, under
// 1 % at orders >= 4); 0 above the largest order with a fitted constant.
// Rectangular cells: at most max_grid_cells^3 cells in all.
int max_grid_cells(int order);

}    // namespace kifmm
