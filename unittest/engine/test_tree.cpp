// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Octree and interaction-list tests (no expansions involved).
#include "interaction_lists.h"
#include "morton.h"
#include "octree.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <map>

using namespace kifmm;
using namespace kifmm_test;

namespace {

struct Built {
  Octree tree;
  InteractionLists lists;
};

Built build(const Points &src, const Points &trg, int leaf, int max_depth = 20)
{
  Built b;
  RootBox root = bounding_cube(src.size(), src.xyz.data(), trg.size(), trg.xyz.data());
  build_octree(b.tree, root, src.size(), src.xyz.data(), trg.size(), trg.xyz.data(), leaf, max_depth);
  build_interaction_lists(b.tree, b.lists);
  return b;
}

// Symbolic count: every (target leaf, source leaf) pair must be covered exactly once by
// U(B), W(B), or V/X of B or of one of its ancestors (a list entry D covers all leaves below D).
void expect_exact_cover(const Built &b)
{
  const auto &cells = b.tree.cells;
  const int n = (int) cells.size();
  std::vector<std::vector<int>> below(n);    // source leaves in the subtree
  for (int c = n - 1; c >= 0; --c) {
    if (cells[c].leaf()) {
      if (cells[c].n_src() > 0) below[c].push_back(c);
    } else {
      for (int k = 0; k < cells[c].n_children; ++k) {
        const auto &v = below[cells[c].first_child + k];
        below[c].insert(below[c].end(), v.begin(), v.end());
      }
    }
  }
  std::vector<int> src_leaves;
  for (int l : b.tree.leaves)
    if (cells[l].n_src() > 0) src_leaves.push_back(l);
  std::vector<int> count(n);
  long checked = 0;
  for (int B : b.tree.leaves) {
    if (cells[B].n_trg() == 0) continue;
    std::fill(count.begin(), count.end(), 0);
    for (const int *a = b.lists.U.begin(B); a != b.lists.U.end(B); ++a) count[*a]++;
    for (const int *d = b.lists.W.begin(B); d != b.lists.W.end(B); ++d)
      for (int a : below[*d]) count[a]++;
    for (int C = B; C >= 0; C = cells[C].parent) {
      for (const int *d = b.lists.V.begin(C); d != b.lists.V.end(C); ++d)
        for (int a : below[*d]) count[a]++;
      for (const int *d = b.lists.X.begin(C); d != b.lists.X.end(C); ++d)
        for (int a : below[*d]) count[a]++;
    }
    for (int a : src_leaves) {
      ASSERT_EQ(count[a], 1) << "target leaf " << B << " source leaf " << a;
      ++checked;
    }
  }
  EXPECT_GT(checked, 0);
  // V entries are at the target's level and not adjacent; X entries coarser leaves, not adjacent;
  // W entries finer, not adjacent; U entries adjacent leaves.
  for (int B = 0; B < n; ++B) {
    for (const int *d = b.lists.V.begin(B); d != b.lists.V.end(B); ++d) {
      EXPECT_EQ(cells[*d].level, cells[B].level);
      EXPECT_FALSE(cells_adjacent(cells[*d], cells[B]));
    }
    for (const int *d = b.lists.X.begin(B); d != b.lists.X.end(B); ++d) {
      EXPECT_LT(cells[*d].level, cells[B].level);
      EXPECT_TRUE(cells[*d].leaf());
      EXPECT_FALSE(cells_adjacent(cells[*d], cells[B]));
    }
    for (const int *d = b.lists.W.begin(B); d != b.lists.W.end(B); ++d) {
      EXPECT_GT(cells[*d].level, cells[B].level);
      EXPECT_FALSE(cells_adjacent(cells[*d], cells[B]));
    }
    for (const int *d = b.lists.U.begin(B); d != b.lists.U.end(B); ++d) {
      EXPECT_TRUE(cells[*d].leaf());
      EXPECT_TRUE(*d == B || cells_adjacent(cells[*d], cells[B]));
    }
  }
}

}    // namespace

TEST(EngineTree, MortonRoundTrip)
{
  for (uint32_t x : {0u, 1u, 5u, 1000u, (1u << 21) - 1})
    for (uint32_t y : {0u, 3u, 77777u, (1u << 21) - 1})
      for (uint32_t z : {0u, 2u, 123456u}) {
        uint32_t a, b, c;
        morton_decode(morton_encode(x, y, z), a, b, c);
        EXPECT_EQ(a, x);
        EXPECT_EQ(b, y);
        EXPECT_EQ(c, z);
      }
  EXPECT_EQ(morton_encode(1, 0, 0), 1u);
  EXPECT_EQ(morton_encode(0, 1, 0), 2u);
  EXPECT_EQ(morton_encode(0, 0, 1), 4u);
  EXPECT_EQ(level_key(2, 5), (1u << 6) | 5u);
}

TEST(EngineTree, RadixSortMatchesStableSort)
{
  std::mt19937_64 g(7);
  for (std::size_t n : {0, 1, 100, 5000}) {
    std::vector<uint64_t> keys(n);
    for (auto &k : keys) k = g() >> (1 + g() % 40);    // many duplicates in high bits
    for (std::size_t i = 0; i + 1 < n; i += 7) keys[i + 1] = keys[i];
    std::vector<uint32_t> ref(n);
    for (std::size_t i = 0; i < n; ++i) ref[i] = (uint32_t) i;
    std::stable_sort(ref.begin(), ref.end(), [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
    std::vector<uint64_t> k2 = keys;
    std::vector<uint32_t> order;
    radix_sort_keys(k2, order);
    EXPECT_EQ(order, ref);
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(k2[i], keys[order[i]]);
  }
}

TEST(EngineTree, LeavesRespectLeafSizeAndContainTheirPoints)
{
  Points p = plummer(20000, 3);
  Built b = build(p, p, 50);
  const auto &cells = b.tree.cells;
  std::size_t ns = 0;
  for (int l : b.tree.leaves) {
    EXPECT_LE(cells[l].n_src(), 50u);
    EXPECT_LE(cells[l].n_trg(), 50u);
    ns += cells[l].n_src();
    double c[3];
    b.tree.center(cells[l], c);
    const double h = b.tree.half_width(cells[l].level);
    for (uint32_t i = cells[l].src_begin; i < cells[l].src_end; ++i) {
      const uint32_t j = b.tree.src_order[i];
      for (int d = 0; d < 3; ++d) {
        EXPECT_GE(p.xyz[3 * j + d], c[d] - h * (1 + 1e-12));
        EXPECT_LE(p.xyz[3 * j + d], c[d] + h * (1 + 1e-12));
      }
    }
  }
  EXPECT_EQ(ns, p.size());
  // children partition the parent's ranges; cells are level ordered
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (cells[c].leaf()) continue;
    uint32_t s = cells[c].src_begin, t = cells[c].trg_begin;
    for (int k = 0; k < cells[c].n_children; ++k) {
      const Cell &ch = cells[cells[c].first_child + k];
      EXPECT_EQ(ch.src_begin, s);
      EXPECT_EQ(ch.trg_begin, t);
      EXPECT_EQ(ch.level, cells[c].level + 1);
      EXPECT_EQ(ch.parent, (int) c);
      s = ch.src_end;
      t = ch.trg_end;
    }
    EXPECT_EQ(s, cells[c].src_end);
    EXPECT_EQ(t, cells[c].trg_end);
  }
}

TEST(EngineTree, ClusteredMatterRefinesOnlyWhereNeeded)
{
  Points p = two_clusters(20000, 5);    // sigma 1e-3, 10 apart
  Built b = build(p, p, 64);
  // ~log2(10 / 1e-3) + a few levels deep, yet few cells (no uniform refinement)
  EXPECT_GE(b.tree.depth, 12);
  EXPECT_LT(b.tree.cells.size(), 3000u);
  expect_exact_cover(b);
}

TEST(EngineTree, CoincidentPointsStopAtMaxDepth)
{
  Points p = uniform_cube(200, 9);
  for (int i = 0; i < 300; ++i) {
    p.xyz.insert(p.xyz.end(), {0.25, 0.25, 0.25});
    p.q.push_back(1.0);
  }
  Built b = build(p, p, 16, 10);
  EXPECT_EQ(b.tree.depth, 10);
  for (int l : b.tree.leaves)
    if (b.tree.cells[l].level < 10) EXPECT_LE(b.tree.cells[l].n_src(), 16u);
  expect_exact_cover(b);
}

TEST(EngineTree, ListsCoverEveryPairExactlyOnce)
{
  for (int leaf : {8, 40}) {
    expect_exact_cover(build(uniform_cube(3000, 1), uniform_cube(3000, 1), leaf));
    expect_exact_cover(build(plummer(3000, 2), plummer(3000, 2), leaf));
    expect_exact_cover(build(plane(3000, 3), plane(3000, 3), leaf));
    expect_exact_cover(build(dipoles(1500, 4), dipoles(1500, 4), leaf));
    expect_exact_cover(build(two_clusters(3000, 6), two_clusters(3000, 6), leaf));
    // separate, differently distributed source and target sets
    expect_exact_cover(build(plummer(2000, 7), uniform_cube(2500, 8, 3.0), leaf));
    expect_exact_cover(build(uniform_cube(500, 10, 0.2), plummer(3000, 11), leaf));
  }
}

TEST(EngineTree, FixedRootBoxIsUsed)
{
  Points p = uniform_cube(1000, 12, 0.5);
  RootBox root;
  root.half_width = 4.0;
  Octree t;
  build_octree(t, root, p.size(), p.xyz.data(), p.size(), p.xyz.data(), 32, 20);
  EXPECT_EQ(t.root.half_width, 4.0);
  // points inside [-0.5,0.5]^3 of a [-4,4]^3 root: all level-3 cells lie in the central 2^3 block
  for (int c = t.level_begin[3]; c < t.level_begin[4]; ++c) {
    EXPECT_TRUE(t.cells[c].ix == 3 || t.cells[c].ix == 4);
    EXPECT_TRUE(t.cells[c].iz == 3 || t.cells[c].iz == 4);
  }
}
