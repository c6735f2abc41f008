// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "interaction_lists.h"

#include <algorithm>
#include <cstdint>

namespace kifmm {

std::size_t InteractionLists::bytes() const
{
  std::size_t b = colleagues.capacity() * sizeof(colleagues[0]);
  for (const CellList *l : {&U, &V, &W, &X}) b += (l->off.capacity() + l->idx.capacity()) * sizeof(int);
  return b;
}

namespace {

void flatten(const std::vector<std::vector<int>> &rows, CellList &out)
{
  out.off.assign(rows.size() + 1, 0);
  for (std::size_t i = 0; i < rows.size(); ++i) out.off[i + 1] = out.off[i] + (int) rows[i].size();
  out.idx.resize(out.off.back());
  for (std::size_t i = 0; i < rows.size(); ++i) std::copy(rows[i].begin(), rows[i].end(), out.idx.begin() + out.off[i]);
}

}    // namespace

void build_interaction_lists(const Octree &tree, InteractionLists &lists)
{
  const auto &cells = tree.cells;
  const int n = (int) cells.size();
  lists.colleagues.assign(n, {});
  for (auto &c : lists.colleagues) c.fill(-1);
  std::vector<std::vector<int>> U(n), V(n), W(n), X(n);
  std::vector<std::vector<int>> coarse_adj(n);    // leaves with sources, coarser than B, adjacent to B
  if (n == 0) return;
  lists.colleagues[0][13] = 0;

  const int nlev = (int) tree.level_begin.size() - 1;
  for (int l = 1; l < nlev; ++l) {
#pragma omp parallel for schedule(dynamic, 16) if (tree.level_begin[l + 1] - tree.level_begin[l] > 512)
    for (int b = tree.level_begin[l]; b < tree.level_begin[l + 1]; ++b) {
      const Cell &B = cells[b];
      const int p = B.parent;
      auto &col = lists.colleagues[b];
      // colleagues: children of the parent's colleagues that touch B
      for (int pc : lists.colleagues[p]) {
        if (pc < 0) continue;
        const Cell &C = cells[pc];
        for (int k = 0; k < C.n_children; ++k) {
          const int d = C.first_child + k;
          const Cell &D = cells[d];
          const int dx = D.ix - B.ix, dy = D.iy - B.iy, dz = D.iz - B.iz;
          if (dx >= -1 && dx <= 1 && dy >= -1 && dy <= 1 && dz >= -1 && dz <= 1)
            col[(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)] = d;
          else if (D.gsrc > 0 && B.n_trg() > 0)
            V[b].push_back(d);    // child of a parent's colleague, not adjacent
        }
      }
      // leaves coarser than B adjacent to parent(B): split into adjacent (kept) and X
      auto consider = [&](int a) {
        if (cells_adjacent(cells[a], B)) coarse_adj[b].push_back(a);
        else if (B.n_trg() > 0) X[b].push_back(a);
      };
      for (int a : coarse_adj[p]) consider(a);
      for (int s = 0; s < 27; ++s) {
        const int pc = lists.colleagues[p][s];
        if (s == 13 || pc < 0) continue;
        if (cells[pc].leaf() && cells[pc].gsrc > 0) consider(pc);
      }
    }
  }
  // U and W for target leaves
#pragma omp parallel for schedule(dynamic, 16) if (tree.leaves.size() > 512)
  for (int li = 0; li < (int) tree.leaves.size(); ++li) {
    const int b = tree.leaves[li];
    const Cell &B = cells[b];
    if (B.n_trg() == 0) continue;
    auto &u = U[b];
    for (int a : coarse_adj[b]) u.push_back(a);
    // descend the colleagues (B itself included: it is a leaf with possibly sources)
    std::vector<int> stack;
    for (int s = 0; s < 27; ++s) {
      const int c = lists.colleagues[b][s];
      if (c < 0 || cells[c].gsrc == 0) continue;
      if (cells[c].leaf()) u.push_back(c);
      else stack.push_back(c);
    }
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      const Cell &C = cells[c];
      for (int k = 0; k < C.n_children; ++k) {
        const int d = C.first_child + k;
        const Cell &D = cells[d];
        if (D.gsrc == 0) continue;
        if (!cells_adjacent(D, B)) W[b].push_back(d);
        else if (D.leaf()) u.push_back(d);
        else stack.push_back(d);
      }
    }
    std::sort(u.begin(), u.end());
    std::sort(W[b].begin(), W[b].end());
  }
  flatten(U, lists.U);
  flatten(V, lists.V);
  flatten(W, lists.W);
  flatten(X, lists.X);
}

void color_mutual_pairs(int n_cells, std::vector<MutualPair> &pairs, std::vector<int> &color_off)
{
  // used[c]: colors taken at cell c, 64 per word (grown on demand)
  std::vector<std::vector<uint64_t>> used(n_cells);
  std::vector<int> color(pairs.size());
  int ncolor = 0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    auto &ua = used[pairs[k].a], &ub = used[pairs[k].b];
    const std::size_t nw = std::max(ua.size(), ub.size()) + 1;
    int c = -1;
    for (std::size_t w = 0; w < nw && c < 0; ++w) {
      const uint64_t taken = (w < ua.size() ? ua[w] : 0) | (w < ub.size() ? ub[w] : 0);
      if (~taken) c = 64 * (int) w + __builtin_ctzll(~taken);
    }
    for (auto *u : {&ua, &ub}) {
      if (u->size() <= (std::size_t) c / 64) u->resize(c / 64 + 1, 0);
      (*u)[c / 64] |= uint64_t(1) << (c % 64);
    }
    color[k] = c;
    ncolor = std::max(ncolor, c + 1);
  }
  color_off.assign(ncolor + 1, 0);
  for (int c : color) ++color_off[c + 1];
  for (int c = 0; c < ncolor; ++c) color_off[c + 1] += color_off[c];
  std::vector<MutualPair> by_color(pairs.size());
  std::vector<int> pos(color_off.begin(), color_off.end() - 1);
  for (std::size_t k = 0; k < pairs.size(); ++k) by_color[pos[color[k]]++] = pairs[k];
  pairs.swap(by_color);
}

bool plan_mutual_open(const Octree &tree, const InteractionLists &lists, MutualPlan &plan, int direct_max)
{
  plan.clear();
  const auto &cells = tree.cells;
  const int n = (int) cells.size();
  if (lists.U.off.size() != (std::size_t) n + 1) return false;
  std::vector<MutualPair> keep;
  std::vector<int> self;
  std::size_t entries = 0, self_entries = 0;
  for (int b : tree.leaves) {
    const Cell &B = cells[b];
    if (B.n_trg() == 0) {
      if (lists.U.size(b) != 0) return false;
      continue;
    }
    if (B.n_src() != B.n_trg() || B.src_begin != B.trg_begin) return false;
    self.push_back(b);
    for (const int *a = lists.U.begin(b); a != lists.U.end(b); ++a) {
      ++entries;
      if (cells[*a].n_trg() == 0) return false;    // a source-only leaf: no mirror entry
      if (*a == b) ++self_entries;
      else if (*a > b) keep.push_back({b, *a, {0, 0, 0}});
    }
  }
  // every entry must have its mirror (b in U(a) <-> a in U(b)); each leaf in its own list once
  if (self_entries != self.size() || entries != self_entries + 2 * keep.size()) return false;
  for (const MutualPair &pr : keep)    // (U rows are sorted)
    if (!std::binary_search(lists.U.begin(pr.b), lists.U.end(pr.b), pr.a)) return false;
  if (direct_max >= 0 && lists.W.off.size() == (std::size_t) n + 1 && lists.X.off.size() == (std::size_t) n + 1) {
    // W entries A of B with A a small leaf <-> X entries B of A (A small leaf: direct X)
    auto small_leaf = [&](int a) { return cells[a].leaf() && (int) cells[a].gtrg <= direct_max; };
    std::size_t nx = 0;
    std::vector<std::vector<int>> xs(n);
    for (int a : tree.leaves)
      if (cells[a].n_trg() > 0 && small_leaf(a)) {
        xs[a].assign(lists.X.begin(a), lists.X.end(a));
        std::sort(xs[a].begin(), xs[a].end());
        nx += xs[a].size();
      }
    std::size_t nw = 0;
    for (int b : tree.leaves) {
      if (cells[b].n_trg() == 0) continue;
      for (const int *a = lists.W.begin(b); a != lists.W.end(b); ++a) {
        if (!small_leaf(*a) || (int) cells[*a].gsrc > direct_max) continue;
        if (cells[*a].n_trg() == 0 || !std::binary_search(xs[*a].begin(), xs[*a].end(), b)) return false;
        keep.push_back({b, *a, {0, 0, 0}});
        ++nw;
      }
    }
    if (nw != nx) return false;
    plan.w_direct_max = direct_max;
  }
  color_mutual_pairs(n, keep, plan.color_off);
  plan.pairs = std::move(keep);
  plan.self_leaves = std::move(self);
  plan.active = true;
  return true;
}

bool plan_mutual_partial(const Octree &tree, const InteractionLists &lists, const std::vector<char> &mutual,
                         MutualPlan &plan)
{
  plan.clear();
  const int n = (int) tree.cells.size();
  if (lists.U.off.size() != (std::size_t) n + 1 || mutual.size() != (std::size_t) n) return false;
  std::vector<MutualPair> keep;
  std::vector<int> self;
  for (int b : tree.leaves) {
    if (!mutual[b]) continue;
    bool has_self = false;
    for (const int *a = lists.U.begin(b); a != lists.U.end(b); ++a) {
      if (*a == b) has_self = true;
      else if (mutual[*a] && *a > b) {
        if (!std::binary_search(lists.U.begin(*a), lists.U.end(*a), b)) return false;    // (U rows are sorted)
        keep.push_back({b, *a, {0, 0, 0}});
      }
    }
    if (!has_self) return false;
    self.push_back(b);
  }
  if (self.empty()) return false;
  color_mutual_pairs(n, keep, plan.color_off);
  plan.pairs = std::move(keep);
  plan.self_leaves = std::move(self);
  plan.leaf_mutual = mutual;
  plan.partial = true;
  plan.active = true;
  return true;
}

}    // namespace kifmm
