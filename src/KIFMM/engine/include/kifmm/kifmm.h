// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Public interface of the KIFMM engine (namespace kifmm, no LAMMPS dependency).
//
// Conventions (stated once, here):
//   Laplace kernel  G(x,y) = 1/|x-y|            (no 4*pi)
//   Yukawa kernel   G(x,y) = exp(-kappa|x-y|)/|x-y|
//   potential  phi_i = sum_j G(x_i, y_j) q_j          over sources j with |x_i-y_j| > 0
//   gradient   g_i   = grad_x phi(x_i)                 (d phi / d x_i, NOT the force)
// Pairs at zero distance are excluded (never inf/NaN); the caller applies all physical
// prefactors (coulomb: F_i = -qqrd2e q_i g_i; gravity: F_i = +G m_i g_i).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace kifmm {

class Communicator;    // communicator.h (MPI implementation: mpi_communicator.h)

enum class KernelType { Laplace, Yukawa };

struct KernelSpec {
  KernelType type = KernelType::Laplace;
  double kappa = 0.0;    // Yukawa screening (1/length); ignored for Laplace
};

struct Options {
  int order = 6;           // points per edge of the equivalent/check surface grid (p)
  int leaf_size = 0;       // max points per leaf (M); 0 = engine default for this order
  // the tree choice's cost of a near-field pair relative to a charge pair (kDipolePairWeight
  // for evaluate_dipoles: their near-field loop costs more per pair, so smaller leaves pay)
  double near_pair_weight = 1.0;
  // the tree choice on several ranks (evaluate_distributed; gather_layout sets it): the largest
  // share of the points one rank holds. Every rank does a single-level grid's whole convolution
  // over the cells and the forward surface transforms of all occupied cells, while the rest of
  // the work goes with the points: the slowest rank's time is the share's part of the rest plus
  // the repeated part, so the model counts the repeated part 1 / share times (P ranks in
  // balance: P times; all points on one rank: once)
  double model_share = 1.0;
  int max_depth = 20;      // hard limit on tree depth (coincident clusters stop here)
  std::string cache_dir;   // on-disk operator cache; empty = in-memory cache only
  // Fixed root box instead of the bounding cube of the points (e.g. a periodic cell).
  // Points outside it are clamped into its boundary cells.
  bool fixed_root = false;
  double root_center[3] = {0.0, 0.0, 0.0};
  double root_half_width = 1.0;
  // Half-widths of the fixed root per axis in units of root_half_width (largest 1): a
  // rectangular root, e.g. the periodic cell of an orthogonal box. Every cell of the tree has
  // this shape; its operators are computed for it (in memory; the on-disk cache holds cubes).
  double root_shape[3] = {1.0, 1.0, 1.0};
  // Periodic in x, y and z with the fixed root as the periodic cell (cube or rectangular box,
  // root_shape); points are wrapped
  // into it. Laplace: tin-foil Ewald sum (k = 0 omitted) with a uniform neutralizing background
  // for a net charge; Yukawa: the lattice sum. Needs fixed_root (see set_root, periodic.h).
  bool periodic = false;
  // Periodic only: 0 = octree; k >= 3 = one level of k^3 cells instead (periodic_grid.h;
  // Laplace and Yukawa; evaluate() and evaluate_distributed(); rectangular cells: k cells along
  // the longest edge, grid_cells_per_axis).
  int periodic_grid = 0;
  // Periodic only: 3 = periodic in x, y and z; 2 = periodic in x and y, open in z (a slab,
  // boundary p p f): the doubly periodic lattice sum (Laplace; no background: a net charge acts
  // as a charged plane), with the single-level grid only (periodic_grid > 0); every point must
  // lie within the fixed root's z extent.
  int periodic_dims = 3;
  // Distributed evaluation: level of the global top tree (0 = from the number of ranks,
  // see distributed.h).
  int top_level = 0;
};

// Timings in seconds and sizes of the last evaluate() call.
struct Stats {
  int depth = 0;
  std::size_t n_cells = 0, n_leaves = 0;
  std::size_t n_sources = 0, n_targets = 0;
  std::size_t coincident_pairs = 0;   // ordered (target, source) pairs at r = 0 that were excluded
                                      // (a point with itself, same arrays, is not counted)
  std::size_t mutual_pairs = 0;       // pairs of distinct adjacent leaves whose near field was
                                      // evaluated once for both sides (sources = targets; 0: one-sided)
  double t_tree = 0, t_lists = 0, t_upward = 0, t_m2l = 0, t_wx = 0, t_downward = 0, t_p2p = 0;
  double t_precompute = 0;            // operator setup in this call (0 when cached)
  std::size_t operator_bytes = 0;     // memory of precomputed operators
  std::size_t tree_bytes = 0;         // memory of tree + expansions in this evaluation
  // distributed evaluation (evaluate_distributed): time in communication calls, bytes this
  // rank sent (of which ghost points, and of which locally essential tree fragments: cells,
  // densities and their points), ghost points received, LET cells received, level of the top tree
  double t_comm = 0;
  std::size_t comm_bytes = 0, ghost_bytes = 0, let_bytes = 0, n_ghosts = 0, let_cells = 0;
  int top_level = 0;
};

class Evaluator {
 public:
  virtual ~Evaluator() = default;

  // Sources (n_src points, xyz interleaved, strengths q) act on targets (n_trg points).
  // pot (n_trg) may be null: then no potential work is done. grad (3*n_trg) may be null.
  // Sources with q == 0 are skipped. Sources and targets may be the same arrays.
  virtual void evaluate(std::size_t n_src, const double *src_xyz, const double *src_q,
                        std::size_t n_trg, const double *trg_xyz, double *pot,
                        double *grad) = 0;

  // Distributed N-body evaluation (collective over comm): every rank passes its own points
  // (all are targets; those with q != 0 are sources) and gets pot/grad of its own points,
  // equal to evaluate() on the union of all ranks' points up to round-off. Memory per rank:
  // its points, ghost points near them, and a top tree that does not grow with N.
  // Open or periodic boundaries (periodic: the fixed root is the cell).
  virtual void evaluate_distributed(Communicator &comm, std::size_t n, const double *xyz, const double *q,
                                    double *pot, double *grad) = 0;

  // Charges and point dipoles (open boundaries): sources with charges q (may be null: none)
  // and dipole moments mu (3 per source, interleaved; may be null: none) act on targets:
  //   pot[i]  = sum_j q_j G(x_i - y_j) + mu_j . grad_y G(x_i - y_j),
  //   grad    = its gradient (3 per target), hess (may be null) its second derivatives,
  //             6 per target in the order xx yy zz xy xz yz (the field gradient is -hess).
  // Sources with q == 0 and mu == 0 are skipped; pairs at r = 0 are excluded. The kernel needs
  // third derivatives (Laplace and Yukawa have them). Open and periodic boundaries (periodic
  // Laplace: tin-foil, as for charges, with the total dipole sum_j q_j y_j + mu_j); one process.
  virtual void evaluate_dipoles(std::size_t n_src, const double *src_xyz, const double *src_q,
                                const double *src_mu, std::size_t n_trg, const double *trg_xyz, double *pot,
                                double *grad, double *hess) = 0;
  // The same distributed (collective over comm, as evaluate_distributed): every rank passes its
  // own points with charges q and moments mu (either may be null: none) and gets pot, grad and
  // hess (each may be null) of its own points from the points of all ranks.
  virtual void evaluate_dipoles_distributed(Communicator &comm, std::size_t n, const double *xyz, const double *q,
                                            const double *mu, double *pot, double *grad, double *hess) = 0;

  virtual const Stats &stats() const = 0;
  virtual const KernelSpec &kernel() const = 0;
  virtual const Options &options() const = 0;
  // New fixed root (e.g. the periodic cell of a box that changed); sets fixed_root.
  // set_root: a cube; set_root_box: a rectangular box of these half-widths per axis.
  virtual void set_root(const double center[3], double half_width) = 0;
  virtual void set_root_box(const double center[3], const double half_widths[3]) = 0;

  // What the periodic virial needs besides the gradients (periodic_point_virial): Laplace,
  // p p p or a slab (periodic_dims 2: the images over the x-y lattice only), single-level grid
  // (Options::periodic_grid > 0) only. Sources = targets = xyz
  // (strengths q; collective over comm when not null, each rank its own points). Per point i:
  //   offset[3i + a]    = (x_i - c_i)_a, c_i the centre of the grid cell of x_i (wrapped);
  //   psi[9i + 3a + b]  = d/dx_b sum_{j, n} q_j (D_n)_a G(x_i - x_j - n L),
  // D_n = c_i - c_j - n L the offset of the two cells' centres (image n of cell j): its far
  // part by a convolution with offset-weighted grid kernels (periodic_grid_moment_kernels), its
  // near part from the 26 neighbour cells. One evaluation with q, then that field.
  virtual void periodic_virial_fields(Communicator *comm, std::size_t n, const double *xyz, const double *q,
                                      double *offset, double *psi) = 0;
  // The same with charges and dipoles (sources and targets may differ, e.g. all points as
  // sources and a rank's own as targets; see comm below): offsets of the sources and of the targets,
  // psi (9 per target) of the sources' charges and dipoles, and its derivatives
  //   chi[18i + 6a + m] = the second derivatives of sum_{j, n} (D_n)_a Phi_{j,n} at x_i
  // (m = xx yy zz xy xz yz), Phi_{j,n} the potential of source j's image n (charge and dipole).
  // With comm (collective, as evaluate_dipoles_distributed): every rank passes its own points as
  // the sources and the targets (the same arrays).
  virtual void periodic_dipole_virial_fields(Communicator *comm, std::size_t n_src, const double *src_xyz,
                                             const double *src_q, const double *src_mu, std::size_t n_trg,
                                             const double *trg_xyz, double *src_offset, double *trg_offset,
                                             double *psi, double *chi) = 0;
};

std::unique_ptr<Evaluator> make_evaluator(const KernelSpec &kernel, const Options &options);

// Exact O(N*M) reference with the same conventions (OpenMP, vectorized).
void direct_sum(const KernelSpec &kernel, std::size_t n_src, const double *src_xyz,
                const double *src_q, std::size_t n_trg, const double *trg_xyz, double *pot,
                double *grad);

// Near-field cost per pair of evaluate_dipoles with second derivatives (mutual loop, charges
// and dipoles) over that of charges (bench/dipoles/results): Options::near_pair_weight of
// dipole evaluations.
constexpr double kDipolePairWeight = 4.0;

// Exact O(N*M) reference of evaluate_dipoles (same conventions; hess may be null).
void direct_sum_dipoles(const KernelSpec &kernel, std::size_t n_src, const double *src_xyz, const double *src_q,
                        const double *src_mu, std::size_t n_trg, const double *trg_xyz, double *pot, double *grad,
                        double *hess);

// All pairs inside one small group of n points (e.g. the pebbles of a rigid body), O(n^2),
// serial, same kernel and conventions as direct_sum (r = 0 pairs excluded): for every point i,
// pot[i] = sum_j q_j G(x_i, x_j), grad[3i..] its gradient, and (when pair_virial is not null)
// the pair virial tensor T_i,ab = sum_j q_j (x_i - x_j)_a dG/dx_i,b (6 values per point in the
// order xx yy zz xy xz yz; symmetric for these radial kernels).
void group_pair_sum(const KernelSpec &kernel, std::size_t n, const double *xyz, const double *q,
                    double *pot, double *grad, double *pair_virial);

// Calibration: smallest-cost (order, leaf size) whose measured relative RMS force error
// is below rel_force_error; also returns the error that was measured for that choice.
// periodic: errors measured with periodic boundaries (larger at the same order). The leaf
// size is the engine default for the order (per order, not per N: see choose_tree).
struct Choice {
  int order;
  int leaf_size;
  double measured_error;
};
Choice choose_order(const KernelSpec &kernel, double rel_force_error, bool periodic = false);
// Highest order of the calibration table (choose_order returns it when no order meets the
// request).
int max_calibrated_order();

// Tree for n points at this order and boundary: the depth of least modelled CPU time for n
// points spread uniformly over the root cube (cost_model.h: near-field pairs, M2L translations
// and cells per depth, constants fitted to measured evaluations), and the leaf size that gives
// that depth (m + 6 sqrt(m) + 3, m = n / 8^depth). Deterministic: the same n gives the same tree on every
// rank. Used by kspace_style kifmm when no leaf size is given.
struct TreeChoice {
  int leaf_size;
  int depth;          // depth of the tree over uniform points (clustered points go deeper)
  double cost;        // modelled CPU seconds of one evaluation (one thread)
  int grid = 0;       // periodic: cells per side of the single-level grid (Options::periodic_grid)
                      // that is cheaper than the octree; 0 = the octree (leaf_size, depth)
};
// grid (periodic): also the single-level grids
// k = 3 .. max_grid_cells(order) on uniform counts (cost_model.h), chosen with the rule of the
// choice from the points below (TreeChoice::grid; the octree's leaf size and depth are kept).
// shape (periodic, Options::root_shape; null: a cube): grids whose cells fit (grid_fits_cell), and in
// cells the octree does not fit (octree_fits_cell) only grids (grid 0 returned: none fits).
TreeChoice choose_tree(int order, std::size_t n, bool periodic, bool grid = false, const double *shape = nullptr,
                       double near_pair_weight = 1.0);

// Periodic cells that are not cubes (Options::root_shape, the half-widths per axis in units of
// the largest): every cell of the octree has the periodic cell's shape, and the single-level
// grid has cells per axis in proportion to the edges (grid_cells_per_axis below).
// Cells whose surfaces take the cell's shape are accurate when nearly cubic (at the same order,
// errors 1.5-3.5x those of cubes when the longest edge is 1.05 times the shortest, 6-60x at
// 1.1): the octree fits periodic cells within max_cell_aspect. The grid's cells may be longer,
// up to max_grid_cell_aspect (grid_near_depth: cubic surfaces and a deeper near field along the
// short axes); grid_fits_cell also bounds the grid's memory at this order.
constexpr double max_cell_aspect = 1.05;
constexpr double max_grid_cell_aspect = 2.0;
bool octree_fits_cell(const double shape[3]);
bool grid_fits_cell(int order, int k, const double shape[3], bool open_z = false);
// A slab (Options::periodic_dims = 2, open_z cells per axis): the grid of least modelled cost
// for n uniformly spread points among those whose cells fit (grid 0: none fits). plan_tree and
// choose_tree take it for slabs.
TreeChoice choose_slab_grid(int order, std::size_t n, const double shape[3]);
// Cells along the longest axis of the grids that fit in the memory bound at this order (kernels
// and convolution buffer at most 64 MB each) in a cell of this shape: 3 .. this. (In cubes and
// nearly cubic cells, where the octree is the alternative, choose_tree offers grids at the
// orders whose grid cost is fitted: 3 to 14.)
int max_grid_cells_long(int order, const double *shape);

// Cells per axis of the grid with k cells along the longest axis of a periodic cell of this
// shape (RootBox::shape, largest 1; null or a cube: k k k): round(k shape[d]), at least 1
// (a thin side of 1 or 2 cells: a cell's near field then holds its own images or one cell
// twice, periodic_grid.h).
inline void grid_cells_per_axis(int k, const double *shape, int cells[3])
{
  for (int d = 0; d < 3; ++d) cells[d] = shape ? std::max(1, (int) std::lround(k * shape[d])) : k;
}
// Half-widths of one cell (largest 1) and the largest one's length in units of the periodic
// cell's half-width H: cell d has half-width H shape[d] / cells[d].
inline double grid_cell_shape(const int cells[3], const double *shape, double cell_shape[3])
{
  double w[3], m = 0;
  for (int d = 0; d < 3; ++d) m = std::max(m, w[d] = (shape ? shape[d] : 1.0) / cells[d]);
  for (int d = 0; d < 3; ++d) cell_shape[d] = w[d] == m ? 1.0 : w[d] / m;
  return m;
}
// Longest over shortest cell edge (1: cubic cells). The choice offers grids whose cells are
// within max_grid_cell_aspect.
inline double grid_cell_aspect(const int cells[3], const double *shape)
{
  double cs[3];
  grid_cell_shape(cells, shape, cs);
  return 1.0 / std::min(cs[0], std::min(cs[1], cs[2]));
}
// The near field of a grid's cells of half-widths cs (grid_cell_shape, largest 1), per axis:
// the cells it reaches on each side (m) and the shape of the cells' surfaces (ss, largest 1).
// Cells within max_cell_aspect: their 26 neighbours (m = 1 1 1), surfaces of the cell's shape.
// Longer ("stretched") cells keep cubic surfaces of their largest half-width, which enclose the
// cell, and along each axis d reach the fewest cells m_d that keep the nearest far cell's centre
// as far as between cubes, 4 largest half-widths: 2 (m_d + 1) cs_d >= 4. The far cells' upward
// equivalent surfaces then stay outside the downward equivalent surface of the target, as in a
// cubic grid (e.g. cells 1 x 1 x 0.75: 3 x 3 x 5 near cells).
inline void grid_near_depth(const double cs[3], int m[3], double ss[3])
{
  const bool stretched = 1.0 / std::min(cs[0], std::min(cs[1], cs[2])) > max_cell_aspect * (1 + 1e-12);
  for (int d = 0; d < 3; ++d) {
    m[d] = stretched ? std::max(1, (int) std::ceil(2.0 / cs[d] - 1.0 - 1e-9)) : 1;
    ss[d] = stretched ? 1.0 : cs[d];
  }
}



// Tree for these n points (N-body: sources = targets = xyz, the evaluator's options: order,
// periodic, root, max_depth; options.leaf_size is ignored): builds the octree and interaction
// lists of the actual points for a few candidate leaf sizes, none below the uniform choice's
// (the leaf sizes of the uniform depths 0 .. d of the uniform choice d, the geometric means
// between neighbouring ones, and the per-order default leaf size), evaluates the same cost
// model on the counts of each actual tree (tree_counts, cost_model.h) and returns the cheapest;
// the uniform choice is kept unless another tree is modelled more than 5 % cheaper (the fit's
// residuals are 4-8 %). depth: of the actual tree. Deterministic for the same points; the
// distributed evaluation (each rank holds its own atoms) takes it on the stand-in of all ranks'
// points (gather_layout below). Costs a few tree builds (bench_engine --tree-choice: "choice s").
// Periodic: also the single-level grids of k^3 cells, k = 3 .. max_grid_cells(order)
// (cost_model.h, counts of the actual cell occupancies); a grid is returned (grid = k, with
// the octree's leaf size and depth kept for the distributed evaluation) when it is modelled
// cheaper than the chosen octree by the same margin.
TreeChoice choose_tree(const KernelSpec &kernel, const Options &options, std::size_t n, const double *xyz);

// Modelled cost and depth of the actual tree of these points with this leaf size (as above).
TreeChoice model_tree(const KernelSpec &kernel, const Options &options, std::size_t n, const double *xyz,
                      int leaf_size);

// The periodic single-level grids the choices above offer, modelled (TreeChoice::grid = k cells
// along the longest axis, leaf_size = options.leaf_size), by ascending k: every k >= 3 whose
// cells fit the periodic cell (grid_fits_cell; a slab, periodic_dims 2: open along z) and, where
// the octree is the alternative (octree_alternative), only at the orders whose grid cost is
// fitted and with at most one cell per point; on the actual cell occupancies of these points or,
// xyz null, on n uniformly spread points. None when the options are not periodic.
std::vector<TreeChoice> model_grids(const KernelSpec &kernel, const Options &options, std::size_t n, const double *xyz,
                                    bool octree_alternative);

// The tree of an N-body evaluation, from what the caller asks for (tree_plan.cpp; what
// kspace_style kifmm uses). A given leaf size is used as is. Otherwise the uniform choice above
// for n points, and the choice from the points at the first evaluation: when one process holds
// all the points (not distributed), choose_tree_from_points; on several ranks, up to
// kLayoutMaxPoints points, choose_tree_from_layout on their stand-in (gather_layout, below).
// grid (periodic only): > 0 the
// single-level grid of grid^3 cells, < 0 chosen with the tree (the octree when a leaf size is
// given), 0 the octree.
struct TreeRequest {
  std::size_t n = 0;          // points of nonzero strength, over all ranks
  int leaf_size = 0;          // > 0: given
  int grid = 0;
  bool distributed = false;   // every rank holds only its own points
};
struct TreePlan {
  Options options;            // the requested options with leaf_size and periodic_grid set
  bool from_points = false;   // choose again from the points at the first evaluation
  TreeChoice uniform{0, -1, 0.0};    // the uniform choice (depth -1: leaf size given)
};
// options: order, periodic, cache and root as they will be used. current: the options of the
// evaluator in use (or null); a plan that waits for the points keeps its leaf size and grid
// when it has the same order, boundary and cache, so that no operators are built until then.
TreePlan plan_tree(const Options &options, const TreeRequest &request, const Options *current = nullptr);
// The choice from the points for a plan with from_points (request as given to plan_tree;
// sources = targets = xyz): options.leaf_size from choose_tree(kernel, options, n, xyz), and
// options.periodic_grid too when the grid is chosen (request.grid < 0). Returns that choice.
TreeChoice choose_tree_from_points(const KernelSpec &kernel, const TreeRequest &request, Options &options,
                                   std::size_t n, const double *xyz);

// ---- the points of all ranks as the tree choice sees them (point_layout.cpp)
// On several ranks each holds only its own points. gather_layout (collective: every rank calls
// it) gives every rank the same stand-in for the points of all ranks: an adaptive histogram over
// the evaluation's root (the periodic cell, or the bounding cube of all points) whose cells are
// split while they hold more than kLayoutCell points, refined on global counts (one reduction
// of the children's counts per level), and each cell's count spread uniformly over it
// (pseudo-random, the same sequence on every rank). An octree of leaf size kLayoutCell or more
// has the same cells with the same counts over the stand-in as over the real points (a cell it
// splits holds more than kLayoutCell points, so its children's counts are in the histogram),
// and so the same modelled cost (tree_counts); a single-level grid's occupancies are
// approximate (the histogram's cells are spread over the grid's cells). Memory: the stand-in
// points (24 bytes each) on every rank, and the trees the choice builds over them, as one rank
// holding all points; none above kLayoutMaxPoints points (xyz empty: the uniform choice stays).
constexpr double kLayoutCell = 8;
constexpr std::size_t kLayoutMaxPoints = 4000000;
struct PointLayout {
  std::size_t n = 0;            // points of all ranks
  std::vector<double> xyz;      // the stand-in points (3 n), empty when there are none
  Options model;                // the options with the evaluation's root fixed and model_share
                                // (the most points on one rank over n): the model's trees
};
PointLayout gather_layout(const KernelSpec &kernel, const Options &options, std::size_t n, const double *xyz,
                          Communicator &comm);
// choose_tree_from_points on the stand-in points (layout.xyz not empty; layout gathered with these options)
TreeChoice choose_tree_from_layout(const KernelSpec &kernel, const TreeRequest &request, Options &options,
                                   const PointLayout &layout);


// ---- tuning the tree by timing (tree_tuning.cpp)
// The cost model's residuals (6-17 % RMS per point set, more for the grid on heaped points at
// low orders) leave its choice up to 1.2x slower than the fastest tree on some sets and orders.
// Tuning times trees near it on real evaluations (their results are used: every tree has the
// same order) and keeps the fastest.
//
// Two ladders of trees: octrees of leaf sizes 2^(j/2) times the one in use (up to 4 distinct
// trees on either side: same depth and modelled cost is the same tree) and, when the grid is
// chosen with the tree (request.grid < 0, periodic), the single-level grids choose_tree offers,
// by cells per side. Modelled on these points (xyz: one process holds all of them, or the
// stand-in of all ranks' points, gather_layout, the same on every rank) or, when xyz is null
// (several ranks beyond kLayoutMaxPoints points), on n uniformly spread points (octrees of
// depths 0 .. log8 n): the same on every rank. The search starts at
// the tree in use (options: its leaf size and grid) and walks its ladder towards the faster
// neighbour until both neighbours of the fastest are slower, and of every tree within kTuneFlat
// of the fastest (flat stretches and bumps of a few per cent, where noise would stop the walk);
// then the same on the other ladder from its tree of least modelled cost, when that is within
// kTuneOtherLadder of the tree in use's modelled cost; on the uniform ladders (xyz null) always,
// since that model cannot see clustering (a Plummer sphere in a periodic cell: octrees twice as
// fast as the grid the uniform model chooses), walked on only while its fastest tree is within
// kTuneSlower of the fastest tree timed. On the points (xyz given), a tree
// modelled at more than kTuneModelled times the tree in use's cost is not timed (slower by more
// than the model's misses; deep trees at high orders take gigabytes); the uniform ladders of
// several ranks (xyz null) are walked without this limit, their model misses more on
// clustered atoms. Each tree is timed after one evaluation
// that warms it up (first-touch memory; not timed) on two evaluations or more, until they add
// up to kTuneMinSeconds (at most kTuneRepeats; the least counts, as the least disturbed by
// other work on the machine; one when it already takes kTuneSlower times the fastest so far),
// at most kTuneTrees trees; the tree in use is kept unless another is faster by kTuneMargin.
// A given leaf size or grid (request) is not tuned.
//
// Per evaluation:
//   select(ev)   before it: ev (the evaluator in use) becomes the one of the tree to time next
//                when that is another tree (built from options with its leaf size and grid;
//                the caller sets a changing root on it as on any evaluator);
//   record(t)    after it: its time in seconds without operator setup (Stats::t_precompute);
//                on several ranks the same value on every rank (the slowest rank's time).
// A tree other than the first (the tree in use at the start, whose accuracy the caller knows)
// may be less accurate (deeper trees: more translations). With an accuracy to keep, after the
// first evaluation of such a tree (new_tree() true, before record) the caller measures its error
// and, when it falls short, calls reject(ev) instead of record: the tree is never timed again
// nor kept, and ev becomes the first tree's evaluator, for the caller to evaluate again.
// When tuning() is false, finish(ev) makes ev the fastest tree's evaluator and returns that tree.
constexpr double kTuneOtherLadder = 1.6;
constexpr double kTuneModelled = 2.0;
constexpr double kTuneSlower = 1.5;
constexpr int kTuneTrees = 12;
constexpr double kTuneMinSeconds = 0.05;
constexpr int kTuneRepeats = 8;
constexpr double kTuneMargin = 0.03;
constexpr double kTuneFlat = 0.05;
class TreeTuner {
 public:
  struct Timed {
    TreeChoice tree;
    double least = 0;    // least time of its evaluations (s)
    double total = 0;    // their sum (s)
    int evaluations = 0;    // the first one not timed (warm-up)
    bool rejected = false;    // its accuracy fell short (reject)
  };
  TreeTuner() = default;
  // model: options to model the trees with (the layout's, PointLayout::model, whose root is
  // fixed), when they differ from the evaluator's (null: options)
  TreeTuner(const KernelSpec &kernel, const TreeRequest &request, const Options &options, std::size_t n,
            const double *xyz, const Options *model = nullptr);
  // on several ranks: the trees modelled on the stand-in of all ranks' points (layout, gathered
  // with these options), or on layout.n uniformly spread points when it has none
  TreeTuner(const KernelSpec &kernel, const TreeRequest &request, const Options &options, const PointLayout &layout);
  bool tuning() const { return !done_; }
  void select(std::unique_ptr<Evaluator> &ev);
  void record(double seconds);
  bool new_tree() const { return tuning() && in_use_ != 0 && timed_[in_use_].evaluations == 0; }
  void reject(std::unique_ptr<Evaluator> &ev);
  TreeChoice finish(std::unique_ptr<Evaluator> &ev);
  const std::vector<Timed> &timed() const { return timed_; }    // in the order timed
  int evaluations() const { return evaluations_; }

 private:
  struct Rung {
    TreeChoice tree;
    int timed = -1;    // index in timed_ (-1: not timed)
  };
  void next_tree();
  bool walk(int ladder);
  bool ladder_behind(int ladder) const;
  void use(std::unique_ptr<Evaluator> &ev, std::size_t i);
  void start(int ladder, std::size_t rung);
  KernelSpec kernel_;
  Options options_;
  std::vector<Rung> ladders_[2];    // 0: octrees by leaf size, 1: grids by cells per side
  std::vector<Timed> timed_;
  int ladder_ = 0;                  // the ladder and rung being timed
  std::size_t rung_ = 0;
  int first_ladder_ = 0;
  long other_start_ = -1;           // the other ladder's start (-1: not searched)
  double cost_limit_ = std::numeric_limits<double>::infinity();    // modelled cost above which a tree is not timed
  bool uniform_ = false;            // the ladders of n uniform points (xyz null)
  std::size_t in_use_ = 0;          // index in timed_ of the evaluator in use
  int evaluations_ = 0;
  bool done_ = true;
};
// options with the leaf size and single-level grid of this tree
Options tree_options(const Options &options, const TreeChoice &tree);

// ---- the order for a requested accuracy, measured on the points (order_search.cpp)

// The measurement kspace_style kifmm makes at the start of a run: the relative error sampled
// on this many targets against their exact values (sampled_relative_error), wanted at this
// fraction of the requested accuracy.
constexpr int order_search_samples = 1000;
constexpr double order_search_margin = 0.75;

// The caller's side of an order search: evaluate at an order (its current tree and points) and
// return the measured relative error there (< 0: not measured); keep the current evaluation
// before another order is tried, and return to the kept one. difference_from_kept: the relative
// RMS difference over ALL points between the current evaluation and the kept one, normalized as
// the measured error (< 0: not available). Of two orders, the lower one's error is at most that
// difference plus the higher one's error: a bound whose large term has no sampling noise.
// step: why the next measure is made (for the caller's log): the order above, as the error
// exceeds the target; the order below, as it is well within; the order above the current
// evaluation, to bound the current one's error more tightly; the order the search returns to.
class OrderTrials {
 public:
  enum class Step { raise, lower, bound, back };
  virtual ~OrderTrials() = default;
  virtual double measure(int order) = 0;
  virtual void keep() = 0;
  virtual void restore() = 0;
  virtual double difference_from_kept() { return -1; }
  virtual void step(Step) {}
};
struct OrderFound {
  int order;
  double error;    // measured at that order
};
// From `at` (an order and its measured error): the next order while the error exceeds
// order_search_margin * request (the sampled error is an estimate), up to max_order. When the
// difference to the next order is available and the bound from it (difference + next order's
// error) meets the request, the order is kept after all (its evaluation restored) with that
// bound as its error. When the bound misses the request and the other side of the triangle
// (difference - next order's error) does not, the order is bounded again from the order above
// the next one (whose error is smaller): kept if that bound meets the request, else the next
// order evaluated again and the search goes on from it.
OrderFound raise_order(OrderTrials &trials, OrderFound at, double request, int max_order);
// raise_order, then, while the error is below half of order_search_margin * request, the order
// below (not below min_order, not above start's), taken if it meets the request (the bound from
// the difference when available, else its measured error below the margin) and its error
// differs from the current one (equal errors: no expansions on this tree, the order is kept),
// else the kept evaluation restored: the lowest order found to meet the request, one step at a
// time. When the bound misses the request and the other side of the triangle (difference -
// current order's error) does not, the order below is bounded again from the order above the
// current one (whose error is smaller): taken if that bound meets the request, else the
// current order evaluated again. Each trial is the caller's evaluation at that order: on the
// tree the caller chooses for it.
OrderFound search_order(OrderTrials &trials, OrderFound start, double request, int min_order, int max_order);

// ---- induced point dipoles (polarization.cpp)

// Point polarizabilities alpha_i >= 0 at n points take the dipoles
//   mu_i = alpha_i (e0_i + e_i(mu)),      e_i(mu) = -grad phi of all the dipoles mu at x_i
// (the field of the other points: pairs at r = 0 are excluded, as in every evaluation), e0 the
// field of everything else (charges, permanent dipoles, an external field). For alpha_i > 0 this
// is the symmetric linear system  mu_i / alpha_i - e_i(mu) = e0_i  (points with alpha_i = 0 keep
// mu_i = 0), positive definite unless the polarizabilities are too large for the distances
// between the points (the polarization catastrophe of point dipoles). Solved by conjugate
// gradients preconditioned with alpha (Jacobi), from the start guess in mu, to
//   residual = sqrt(sum_i alpha_i |r_i|^2 / sum_i alpha_i |e0_i|^2) <= tolerance,
// r = e0 - (mu / alpha - e(mu)) the residual field.
// field(mu, e): e = -grad phi of the dipoles mu (3 per point) at the n points: the caller's
// evaluation (one process or, each process its own points, several). sum(x): x summed over the
// processes (x itself on one). Collective when the evaluation is.
struct PolarizationSolve {
  int iterations = 0;     // conjugate-gradient steps
  int evaluations = 0;    // calls of field()
  double residual = 0;    // relative residual of the returned mu (as above)
  bool converged = false;
  bool indefinite = false;    // a direction of non-positive curvature: the system has no minimum
};
PolarizationSolve solve_induced_dipoles(std::size_t n, const double *alpha, const double *e0,
                                        const std::function<void(const double *mu, double *e)> &field,
                                        const std::function<double(double)> &sum, double tolerance,
                                        int max_iterations, double *mu);

// ---- dielectric spheres: surface polarization by a boundary integral equation
//      (dielectric_spheres.cpp)

// n spheres (centres, radii, permittivity eps_ratio = eps_in / eps_out each) in a medium of
// permittivity eps_out and a uniform external field E0: the surface charge density sigma of
// each sphere (bound charge in units of eps_out: the potential is
// phi(x) = -E0 . x + sum_spheres int sigma(y) / (4 pi |x - y|) dS_y) solves the second-kind
// equation of the normal field's jump at a dielectric interface (Greengard and Moura 1994)
//   sigma(x) - 2 lambda n(x) . E_pv[sigma](x) = 2 lambda n(x) . E0,
//   lambda = (eps_ratio - 1) / (eps_ratio + 1),
// E_pv the principal-value field of all sigma on the surfaces. Each sphere carries 2 (L + 1)^2
// nodes (L = degree; sphere_grid.h) with its pole towards its nearest neighbour; a sphere with
// exactly one close neighbour has them drawn towards the contact by a conformal map (options:
// contact_refinement), which keeps the own-sphere operator exact:
//   own sphere    : sigma lambda^(3/2) of degree <= L (lambda the map's length scale), whose
//                   principal-value normal field is diagonal in the harmonics (Y_lm / (2 (2l + 1))
//                   on the plain grid);
//   other spheres : the nodes as point charges through the evaluator (FMM, Laplace) or the
//                   direct sum; nodes closer to another sphere than 4 pi a / (L + 1) of its
//                   radius a (touching or nearly touching spheres) take that sphere's field
//                   from its sigma interpolated by its harmonics on a quadrature graded
//                   towards the node's nearest surface point (precomputed once per solve).
// Two touching spheres of permittivity ratio 10: force within 0.4 % of the exact value at
// L = 12, 0.04 % at L = 16 (a gap of 0.05 radii: 7e-5 and 2e-6; bench/dielectric/results).
// Solved by GMRES from the isolated spheres' solution 3 (eps - 1) / (eps + 2) E0 . n. Forces,
// torques and dipoles are those of the surface charges in the field of everything else
// (E0 and the other spheres): F_i = int_i sigma E dS, in units of eps_out (times eps_0 eps_out
// in SI; times epsilon / (4 pi) in LAMMPS's Gaussian-like real/metal units where a unit
// charge's potential is qqrd2e q / r).
struct DielectricSphereOptions {
  int degree = 12;             // L: harmonics per sphere up to this degree (nodes 2 (L + 1)^2)
  double tolerance = 1e-8;     // GMRES: relative residual
  int max_iterations = 300;
  // s: the grid of a sphere with exactly one close neighbour is drawn towards the contact by
  // the factor s (nodes s times denser there, s times sparser on the far side); 0: chosen from
  // the gap (2 to 4); 1: none
  double contact_refinement = 0.0;
  // overlapping spheres (granular contacts): solved as touching, each sphere's radius reduced by
  // half of its largest overlap (DielectricSphereSolve::radius); false: an overlap is an error
  bool touch_overlaps = false;
};
struct DielectricSphereSolve {
  int iterations = 0, evaluations = 0;    // GMRES steps; field evaluations (FMM or direct)
  double residual = 0;
  bool converged = false;
  std::size_t nodes_per_sphere = 0, near_rows = 0;    // near_rows: nodes with a graded quadrature
  double seconds_setup = 0, seconds_solve = 0;        // wall clock: grids and near rows; GMRES and forces
  std::vector<double> node_xyz;    // 3 per node, sphere-major
  std::vector<double> node_area;   // surface element of each node (sum: 4 pi a^2 per sphere)
  std::vector<double> sigma;       // surface charge density at the nodes (units of eps_out)
  std::vector<double> force, torque, dipole;    // 3 per sphere (torque and dipole about the centre)
  std::vector<double> radius;                   // the radii solved with (touch_overlaps)
  std::vector<double> refinement;               // each sphere's factor s (1: its grid is not drawn)
  std::size_t overlapping_pairs = 0;            // pairs solved as touching (touch_overlaps)
};
// ev: a Laplace evaluator (its order sets the accuracy of the far field), or null for the
// direct sum. Throws std::invalid_argument on bad input (overlapping spheres without
// touch_overlaps, radius or eps_ratio not positive, degree < 1, an evaluator of another kernel).
DielectricSphereSolve polarize_dielectric_spheres(Evaluator *ev, std::size_t n, const double *center,
                                                  const double *radius, const double *eps_ratio,
                                                  const double field[3], const DielectricSphereOptions &options);
}    // namespace kifmm

namespace kifmm {

// ---- what a caller needs besides the potentials and gradients (diagnostics.cpp)

// Memory (bytes) one evaluation with these options takes for n_sources points on a process,
// given the memory of its precomputed operators (Stats::operator_bytes): points, cells with
// their densities and FFT spectra, periodic grid spectra, operators.
double estimate_memory_bytes(const Options &options, std::size_t n_sources, std::size_t operator_bytes);

// Per-point virial of the N-body sum (sources = targets = xyz, strengths q) whose gradients
// `grad` an evaluation gave, the force of point i being prefactor * q_i * grad_i:
//   virial[6i + ab] = 1/2 sum_j (x_i - x_j)_a F_ij,b   (xx yy zz xy xz yz; origin independent)
// computed as 1/2 [(x_i - c)_a F_i,b - prefactor q_i d_b psi_a(x_i)], psi_a the potential of
// the strengths q_j (x_j - c)_a, c (returned) the centre of the points' bounding box: three more
// gradient evaluations. comm: distributed over its ranks (each its own points), or null.
// Open boundaries only (the periodic sum has no per-pair form).
void point_virial(Evaluator &ev, Communicator *comm, std::size_t n, const double *xyz,
                  const double *q, const double *grad, double prefactor, double *virial,
                  double center[3]);

// Per-point virial of the periodic sum (Laplace, p p p or a slab, the single-level grid), in the form and
// order of point_virial: virial[6i + ab] = 1/2 sum_{j, n} (x_i - x_j - n L)_a F_ijn,b over all
// images n (the pair i, i at n = 0 excluded). With u_i = x_i - c_i (c_i the centre of i's grid
// cell) the separation is u_i - u_j + D_n, so
//   virial_i,ab = prefactor q_i / 2 [u_i,a grad_i,b - d_b phi_a(x_i) + psi_i,ab]
// with phi_a the periodic potential of the strengths q_j u_j,a (three more gradient
// evaluations) and psi the offset-weighted field of periodic_virial_fields (one evaluation and
// three convolutions). The sum over i is the virial tensor -dU/d(strain); its trace is the
// energy (Coulomb: degree -1). `grad`: the gradients of q at xyz; `offset` (3n, may be null)
// returns u_i.
void periodic_point_virial(Evaluator &ev, Communicator *comm, std::size_t n, const double *xyz,
                           const double *q, const double *grad, double prefactor, double *virial,
                           double *offset = nullptr);

// Charges and dipoles, open boundaries (dipole_virial.cpp; one process; sources all points,
// targets a subset or all): virial[6k + m] = prefactor / 2 sum_j (x_k - y_j)_a F_b (F = (q_k d +
// mu_k . grad d) d_b of the potential of j; ab = xx yy zz xy xz yz, xy = r_x F_y as LAMMPS's pair
// styles tally it), from the evaluation's grad and hess at the targets and three dipole
// evaluations of the sources' strengths times their offsets from center (any point; near the
// points for round-off).
void dipole_point_virial(Evaluator &ev, std::size_t n_src, const double *src_xyz, const double *src_q,
                         const double *src_mu, std::size_t n_trg, const double *trg_xyz, const double *trg_q,
                         const double *trg_mu, const double *grad, const double *hess, double prefactor,
                         double *virial, const double center[3]);
// The same distributed (collective over comm, evaluate_dipoles_distributed): every rank passes
// its own points, which are its sources and its targets; center the same on every rank.
void dipole_point_virial(Evaluator &ev, Communicator &comm, std::size_t n, const double *xyz, const double *q,
                         const double *mu, const double *grad, const double *hess, double prefactor, double *virial,
                         const double center[3]);
// The same periodic (p p p or a slab, Laplace, on the grid; dipole_virial.cpp):
// virial[6k + m] = prefactor / 2 sum_{j, n} (r_n)_a F_b (ab = xx yy zz xy xz yz; r_n = x_k - y_j - n L,
// F = (q_k d + mu_k . grad d) d_b of the potential of image n of j), from the evaluation's grad and
// hess at the targets, periodic_dipole_virial_fields and three dipole evaluations of the
// sources' strengths times their offsets. Not symmetric: the torques make xy differ from yx; xy is
// r_x F_y as LAMMPS's pair styles tally it.
void periodic_dipole_point_virial(Evaluator &ev, std::size_t n_src, const double *src_xyz, const double *src_q,
                                  const double *src_mu, std::size_t n_trg, const double *trg_xyz,
                                  const double *trg_q, const double *trg_mu, const double *grad,
                                  const double *hess, double prefactor, double *virial);
// The same distributed (collective over comm): every rank passes its own points, which are its
// sources and its targets.
void periodic_dipole_point_virial(Evaluator &ev, Communicator &comm, std::size_t n, const double *xyz,
                                  const double *q, const double *mu, const double *grad, const double *hess,
                                  double prefactor, double *virial);

// Sampled error check. exact_gradient: the exact gradient at n_trg targets of the sources
// (open: direct_sum; the evaluator's periodic cell: the Ewald sum of periodic.h, or, where
// reference_order is not 0, the engine at that order); with comm, collective: every rank
// passes its own sources and targets and gets the gradient of all ranks' sources at its targets.
void exact_gradient(const Evaluator &ev, Communicator *comm, std::size_t n_src,
                    const double *src_xyz, const double *src_q, std::size_t n_trg,
                    const double *trg_xyz, double *grad);
// 0 where exact_gradient and exact_dipole_field (of n_src sources at n_trg targets, per rank)
// sum exactly; else the order of the engine evaluation they take as the reference: 14 in a periodic box (p p p) above
// 5e6 source-target pairs when the evaluator's order is 11 or below (it agrees with the Ewald
// sum to 1e-11 .. 4e-11; the Ewald sum costs O(n_src n_trg) erfc terms, 35 s for 1000 targets
// of 1e5 sources on one core, the engine 0.6 s).
int reference_order(const Options &opt, std::size_t n_src, std::size_t n_trg);
// The same for charges and dipoles: the exact gradient and second derivatives at the targets
// (open: direct_sum_dipoles; p p p: an Ewald sum with the engine's conventions, or where
// reference_order is not 0 the engine at that order; a slab or periodic yukawa: the engine at
// order 14, 1e-10 in the tests); with comm as exact_gradient.
void exact_dipole_field(const Evaluator &ev, Communicator *comm, std::size_t n_src, const double *src_xyz,
                        const double *src_q, const double *src_mu, std::size_t n_trg, const double *trg_xyz,
                        double *grad, double *hess);
// `want` of the candidates at random, without replacement (all when want >= their number).
std::vector<std::size_t> sample_without_replacement(std::vector<std::size_t> candidates,
                                                    std::size_t want, unsigned long long seed);
// sqrt(diff2 / ref2) (0 / 0 = 0, x / 0 = inf)
double relative_rms(double diff2, double ref2);
// Relative RMS error of all n_all points from a sample of n_sampled (-1: none): every point
// sampled, the exact ratio; else the squared error of the sample scaled to all points over the
// squared evaluated values of all points (the squared values are dominated by the few points
// with a close neighbour, which a sample mostly misses or overweights, while the far-field
// error is spread over all points).
double sampled_relative_error(double sample_diff2, double sample_ref2, double n_sampled,
                              double n_all, double all_evaluated2);

}    // namespace kifmm
