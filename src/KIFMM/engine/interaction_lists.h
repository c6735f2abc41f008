// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Adaptive interaction lists (Ying, Biros, Zorin 2004) for a target cell B:
//   U(B)  (B leaf)  source leaves adjacent to B, B itself included          -> P2P
//   V(B)            children of the colleagues of parent(B) not adjacent to B -> M2L
//   W(B)  (B leaf)  descendants A of B's colleagues, A not adjacent to B but
//                   parent(A) adjacent to B                                   -> M2P (or P2P)
//   X(B)            leaves A coarser than B, adjacent to parent(B), not adjacent to B -> P2L
// Only cells holding sources (Cell::gsrc) enter a list, and only cells holding targets here
// (n_trg() > 0) get lists, so a
// target leaf receives every source exactly once through U, W of itself and V, X of itself
// and its ancestors (tested symbolically in unittest/engine/test_tree.cpp).
// Colleagues: the (up to) 27 same-level cells touching B, by offset slot
// (dx+1)*9 + (dy+1)*3 + (dz+1); slot 13 is B itself; -1 when absent. Open and periodic
// boundaries share the builder: an image policy (OpenImages, PeriodicImages) says which
// images of the cells are neighbours.
#pragma once

#include "octree.h"

#include <array>
#include <vector>

namespace kifmm {

struct CellList {                 // compressed rows: cells of row i are idx[off[i]..off[i+1])
  std::vector<int> off, idx;
  int size(int i) const { return off[i + 1] - off[i]; }
  const int *begin(int i) const { return idx.data() + off[i]; }
  const int *end(int i) const { return idx.data() + off[i + 1]; }
};

struct InteractionLists {
  std::vector<std::array<int, 27>> colleagues;
  CellList U, V, W, X;
  std::size_t bytes() const;
};

// Compressed rows of (cell, root shift) entries; shift has 3 values in {-1,0,1} per entry.
struct ImageList {
  std::vector<int> off, idx;
  std::vector<signed char> shift;
  int size(int i) const { return off.empty() ? 0 : off[i + 1] - off[i]; }
  int begin(int i) const { return off[i]; }
  int end(int i) const { return off[i + 1]; }
  const signed char *shift_of(int e) const { return &shift[3 * (std::size_t) e]; }
};

// List entries whose source cell is an image of a tree cell (periodic boundaries: the root is
// the periodic cell and a colleague across its faces is an image with a root shift n in
// {-1,0,1}^3). Entries with n = 0 are in InteractionLists; these hold the ones with n != 0.
struct ImageLists {
  ImageList U, W, X;
  std::vector<signed char> V_shift;    // shift of every entry of InteractionLists::V (tests)
};

// Image policies of the list builder: which images of the cells exist.
//   OpenImages      no images: the root has no colleagues but itself, every shift is 0;
//   PeriodicImages  the colleague of cell B at offset d is the cell at B + d modulo the cells
//                   of the level, an image with the root shift of colleague_shift; the root's
//                   27 colleagues are its own images.
struct OpenImages {
  static constexpr bool kImages = false;
  static void root_colleagues(std::array<int, 27> &col) { col[13] = 0; }
  static void shift(const Cell &, int, signed char s[3]) { s[0] = s[1] = s[2] = 0; }
  static bool adjacent(const Cell &a, const signed char *, const Cell &b) { return cells_adjacent(a, b); }
};

// Root shift of the colleague at slot s ((dx+1)*9+(dy+1)*3+(dz+1)) of cell c (periodic tree).
void colleague_shift(const Cell &c, int slot, int shift[3]);

struct PeriodicImages {
  static constexpr bool kImages = true;
  static void root_colleagues(std::array<int, 27> &col) { col.fill(0); }
  static void shift(const Cell &c, int slot, signed char s[3])
  {
    int t[3];
    colleague_shift(c, slot, t);
    for (int k = 0; k < 3; ++k) s[k] = (signed char) t[k];
  }
  static bool adjacent(const Cell &a, const signed char *s, const Cell &b) { return cells_adjacent_shifted(a, s, b); }
};

// The list builder: U, V, W, X and colleagues of every cell under the image policy; entries
// with a nonzero shift go to `images` (PeriodicImages; null with OpenImages). Plain U and W
// rows are sorted by cell, V and X rows and the image rows are in build order (deterministic).
template <class Images> void build_lists(const Octree &tree, InteractionLists &lists, ImageLists *images);

// Open boundaries: build_lists<OpenImages>. (Periodic: build_periodic_interaction_lists, periodic.h.)
void build_interaction_lists(const Octree &tree, InteractionLists &lists);

// Mutual near field (sources and targets are the same points): every unordered pair of
// adjacent leaves is evaluated once for both sides (p2p_mutual.h). A pair: leaf a sees the
// sources of leaf b at their image + shift * L, leaf b those of a at - shift * L (shift = 0
// with open boundaries; periodic.h fills nonzero ones).
struct MutualPair {
  int a, b;
  signed char shift[3];
};

// Pairs grouped by color: pairs of one color share no leaf, so they run in parallel, and
// every target accumulates in the fixed color order (results independent of the threads).
struct MutualPlan {
  bool active = false;
  std::vector<MutualPair> pairs;    // by color
  std::vector<int> color_off;       // pairs of color c: [color_off[c], color_off[c+1])
  std::vector<int> self_leaves;     // leaves with targets (each with itself, one round)
  int w_direct_max = -1;            // open plan: W/X leaf pairs of at most this many points included
  // partial plan (distributed evaluation): only the U pairs of leaves marked in leaf_mutual are
  // in the plan, the leaf pass evaluates the other U entries one-sided
  bool partial = false;
  std::vector<char> leaf_mutual;    // per cell (partial plans)
  void clear()
  {
    active = false;
    partial = false;
    w_direct_max = -1;
    pairs.clear();
    color_off.clear();
    self_leaves.clear();
    leaf_mutual.clear();
  }
};

// Greedy edge coloring of `pairs` (cells < n_cells) in their given order (deterministic):
// each pair takes the lowest color free at both of its leaves; no limit on the number of
// colors (adaptive trees: a coarse leaf may touch many fine ones). Reorders `pairs` by color.
void color_mutual_pairs(int n_cells, std::vector<MutualPair> &pairs, std::vector<int> &color_off);

// Mutual plan of the open-boundary U lists of a tree whose sources and targets are the same
// points in the same order (checked by the caller): every leaf with targets must have equal
// source and target ranges, and U must be symmetric (each leaf in its own list once). Returns
// false (plan inactive) otherwise. direct_max >= 0 also takes the W entries that the leaf pass
// evaluates directly and whose dual X entries are direct too: A in W(B) with A a leaf of at
// most direct_max points (then B in X(A), and X(A) of such a leaf is evaluated directly);
// the plan is dropped unless W and X are exact duals there. The lists are not changed: the
// leaf pass skips U, those W entries and the direct X entries when the plan is active
// (plan.w_direct_max).
bool plan_mutual_open(const Octree &tree, const InteractionLists &lists, MutualPlan &plan, int direct_max = -1);

// Partial mutual plan of open-boundary U lists (distributed evaluation, where the sources also
// hold ghost points that are not targets): leaves with mutual[c] set hold the same points in the
// same order as sources and as targets (checked by the caller); every unordered pair of such
// leaves in U (and each with itself) is in the plan, the other U entries are left to the
// one-sided leaf pass. Accumulators are addressed by the target ranges. Returns false (plan
// inactive) if no leaf qualifies or U is not symmetric between two marked leaves.
bool plan_mutual_partial(const Octree &tree, const InteractionLists &lists, const std::vector<char> &mutual,
                         MutualPlan &plan);

}    // namespace kifmm
