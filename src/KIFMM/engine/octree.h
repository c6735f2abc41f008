// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Adaptive octree over sources and targets (separate point sets, one tree).
//
// Points get their 63-bit Morton key; cells are made top down, level by level: a cell that
// splits has its points partitioned by the next 3-bit key digit (an MSD radix sort that stops
// at the leaves, parallel over the cells of a level). A cell is split while it holds more than
// leaf_size sources or more than leaf_size targets and level < max_depth. Empty children are
// not created. Cells are stored level by level (level_begin), the children of a cell are
// contiguous, and every cell owns a contiguous range of the sorted sources and of the sorted
// targets. The root is the bounding cube of all points, or a fixed box (periodic later).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace kifmm {

// Root box: center and half-width; shape: the half-widths per axis in units of half_width
// (largest 1): a rectangular root (the periodic cell of an orthogonal box). Cells at every
// level have the root's shape; Morton keys and anchors are taken in the root's unit coordinates.
struct RootBox {
  double center[3] = {0, 0, 0};
  double half_width = 1.0;
  double shape[3] = {1.0, 1.0, 1.0};
  bool cubic() const { return shape[0] == 1.0 && shape[1] == 1.0 && shape[2] == 1.0; }
};

struct Cell {
  uint64_t prefix = 0;        // Morton prefix at this level (see morton.h)
  int level = 0;
  int parent = -1;
  int first_child = -1;       // children are cells[first_child .. first_child + n_children)
  int n_children = 0;
  int child[8] = {-1, -1, -1, -1, -1, -1, -1, -1};    // by octant (bit0 x, bit1 y, bit2 z)
  int ix = 0, iy = 0, iz = 0;                         // integer anchor at this level
  uint32_t src_begin = 0, src_end = 0;                // range in sorted sources
  uint32_t trg_begin = 0, trg_end = 0;                // range in sorted targets
  // Counts of the whole (global) tree, which decide list membership and direct-vs-expansion
  // choices. Serial trees: equal to n_src(), n_trg(). Distributed trees (see TopTree): the
  // reduced counts for top cells; the local ranges then hold only this rank's part.
  uint32_t gsrc = 0, gtrg = 0;
  bool pruned = false;    // split in the global tree, children not held here (distributed)
  bool leaf() const { return n_children == 0 && !pruned; }
  uint32_t n_src() const { return src_end - src_begin; }
  uint32_t n_trg() const { return trg_end - trg_begin; }
};

// Child of cell P (index parent) in octant oct (bit0 x, bit1 y, bit2 z): level, parent, Morton
// prefix and anchor; counts and ranges left empty.
inline Cell child_cell(const Cell &P, int parent, int oct)
{
  Cell ch;
  ch.level = P.level + 1;
  ch.parent = parent;
  ch.prefix = (P.prefix << 3) | (uint64_t) oct;
  ch.ix = 2 * P.ix + (oct & 1);
  ch.iy = 2 * P.iy + ((oct >> 1) & 1);
  ch.iz = 2 * P.iz + ((oct >> 2) & 1);
  return ch;
}

struct Octree {
  RootBox root;
  int depth = 0;                      // deepest level present
  std::vector<Cell> cells;            // level-ordered; cells[0] is the root
  std::vector<int> level_begin;       // cells of level l: [level_begin[l], level_begin[l+1])
  std::vector<int> leaves;            // indices of leaf cells
  std::vector<uint32_t> src_order;    // sorted position -> input source index
  std::vector<uint32_t> trg_order;    // sorted position -> input target index
  std::vector<int> top_index;         // distributed: index in the TopTree, -1 below it (else empty)

  // half-width of the cells of a level (times root.shape[d] along axis d)
  double half_width(int level) const { return root.half_width / double(uint64_t(1) << level); }
  // edge of the root along axis d (the period of a periodic root)
  double period(int d) const { return 2.0 * root.half_width * root.shape[d]; }
  void center(const Cell &c, double out[3]) const;
  std::size_t bytes() const;
};

// Global top of a distributed tree, the same on every rank: cells of the global (serial) tree,
// refined from the root where the global counts are large (see distributed.h), in the order
// build_octree makes them (level by level, children by octant). Cells without children here
// are the "frontier": global leaves, or cells that split further in the global tree
// (open[i] = 1), below which the tree is built from the points a rank holds.
struct TopTree {
  int top_level = 0;          // deepest level of the top tree
  std::vector<Cell> cells;    // structure + gsrc/gtrg; point ranges unused
  std::vector<char> open;
};

// Bounding cube of the points (slightly enlarged so every point is strictly inside).
RootBox bounding_cube(std::size_t n_src, const double *src_xyz, std::size_t n_trg,
                      const double *trg_xyz);

// Bounding cube from the coordinate bounds (lo/hi over all points; same result as above).
RootBox bounding_cube_of(const double lo[3], const double hi[3]);

// Root box of one evaluation: the given box when fixed (fixed_center, fixed_half_width and
// fixed_shape (null: a cube): the periodic cell or a user root), else the bounding cube of the points, its half-width rounded
// up to a power of two when the kernel's operators depend on the box size (Yukawa: kappa h),
// so that the boxes of every level come from a fixed ladder of sizes and operator sets are
// reused when the points move between calls. Used by the evaluator and by the tree choice.
RootBox evaluation_root(bool fixed, const double fixed_center[3], double fixed_half_width,
                        const double *fixed_shape, bool size_dependent_operators, std::size_t n_src, const double *src_xyz,
                        std::size_t n_trg, const double *trg_xyz);

// Build the tree. Points outside a given root box are clamped into its boundary cells.
// With `top` (distributed): the top tree is copied (all its cells, empty here or not, their
// split decisions and counts; tree.top_index maps cells to top cells, -1 below the top); an
// open frontier cell splits by the usual rule if it holds points here, else it is pruned.
void build_octree(Octree &tree, const RootBox &root, std::size_t n_src, const double *src_xyz,
                  std::size_t n_trg, const double *trg_xyz, int leaf_size, int max_depth,
                  const TopTree *top = nullptr);

// Morton keys (full depth) of points in a root box, and a stable LSD radix sort of them (a full
// sort, e.g. for partitioning by key ranges; the tree build itself partitions top down).
void morton_keys(const RootBox &root, std::size_t n, const double *xyz, std::vector<uint64_t> &keys);
void radix_sort_keys(std::vector<uint64_t> &keys, std::vector<uint32_t> &order);

// True when closed cells a and b touch or overlap (any level).
bool cells_adjacent(const Cell &a, const Cell &b);

// Periodic trees (root = periodic cell): closed cell a moved by shift root periods (each in
// {-1, 0, 1}) and cell b touch or overlap.
bool cells_adjacent_shifted(const Cell &a, const signed char shift[3], const Cell &b);

}    // namespace kifmm
