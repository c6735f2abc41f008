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
// (dx+1)*9 + (dy+1)*3 + (dz+1); slot 13 is B itself; -1 when absent.
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

void build_interaction_lists(const Octree &tree, InteractionLists &lists);

}    // namespace kifmm
