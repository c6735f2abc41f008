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

void colleague_shift(const Cell &c, int slot, int shift[3])
{
  const int d[3] = {slot / 9 - 1, (slot / 3) % 3 - 1, slot % 3 - 1};
  const int a[3] = {c.ix, c.iy, c.iz};
  const long long n = 1LL << c.level;
  for (int k = 0; k < 3; ++k) {
    const long long g = a[k] + d[k];
    shift[k] = g < 0 ? -1 : (g >= n ? 1 : 0);
  }
}

namespace {

struct Entry {
  int cell;
  signed char s[3];
};
using Rows = std::vector<std::vector<Entry>>;

bool zero_shift(const signed char s[3])
{
  return s[0] == 0 && s[1] == 0 && s[2] == 0;
}

// Rows of entries into compressed rows: shift 0 -> plain (sorted by cell when sort_plain),
// others -> img (build order). img null: every shift is 0.
void split(const Rows &rows, CellList &plain, ImageList *img, bool sort_plain)
{
  const std::size_t n = rows.size();
  plain.off.assign(n + 1, 0);
  if (img) img->off.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    int ni = 0;
    if (img)
      for (const Entry &e : rows[i]) ni += !zero_shift(e.s);
    plain.off[i + 1] = plain.off[i] + (int) rows[i].size() - ni;
    if (img) img->off[i + 1] = img->off[i] + ni;
  }
  plain.idx.resize(plain.off.back());
  if (img) {
    img->idx.resize(img->off.back());
    img->shift.resize(3 * (std::size_t) img->off.back());
  }
  for (std::size_t i = 0; i < n; ++i) {
    int kp = plain.off[i], ki = img ? img->off[i] : 0;
    for (const Entry &e : rows[i]) {
      if (!img || zero_shift(e.s)) {
        plain.idx[kp++] = e.cell;
      } else {
        img->idx[ki] = e.cell;
        std::copy(e.s, e.s + 3, &img->shift[3 * (std::size_t) ki]);
        ++ki;
      }
    }
    if (sort_plain) std::sort(plain.idx.begin() + plain.off[i], plain.idx.begin() + plain.off[i + 1]);
  }
}

// Colleagues, V and the coarse leaves (adjacent to B: coarse_adj; else X) of cell b.
template <class Images>
void colleagues_v_x(const Octree &tree, InteractionLists &lists, int b, Rows &V, Rows &X, Rows &coarse_adj)
{
  const auto &cells = tree.cells;
  const Cell &B = cells[b];
  const int p = B.parent;
  const Cell &P = cells[p];
  auto &col = lists.colleagues[b];
  const int64_t period = int64_t(1) << B.level;
  // colleagues: children of the parent's colleagues (images) that touch B
  for (int s = 0; s < 27; ++s) {
    const int pc = lists.colleagues[p][s];
    if (pc < 0) continue;
    Entry e{-1, {0, 0, 0}};
    Images::shift(P, s, e.s);
    const Cell &C = cells[pc];
    for (int k = 0; k < C.n_children; ++k) {
      e.cell = C.first_child + k;
      const Cell &D = cells[e.cell];
      const int64_t dx = D.ix + e.s[0] * period - B.ix, dy = D.iy + e.s[1] * period - B.iy,
                    dz = D.iz + e.s[2] * period - B.iz;
      if (dx >= -1 && dx <= 1 && dy >= -1 && dy <= 1 && dz >= -1 && dz <= 1)
        col[(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)] = e.cell;
      else if (D.gsrc > 0 && B.n_trg() > 0)
        V[b].push_back(e);    // child of a parent's colleague, not adjacent
    }
  }
  // leaves coarser than B adjacent to parent(B): split into adjacent (kept) and X
  auto consider = [&](const Entry &a) {
    if (Images::adjacent(cells[a.cell], a.s, B)) coarse_adj[b].push_back(a);
    else if (B.n_trg() > 0) X[b].push_back(a);
  };
  for (const Entry &a : coarse_adj[p]) consider(a);
  for (int s = 0; s < 27; ++s) {
    const int pc = lists.colleagues[p][s];
    if (s == 13 || pc < 0) continue;
    if (cells[pc].leaf() && cells[pc].gsrc > 0) {
      Entry e{pc, {0, 0, 0}};
      Images::shift(P, s, e.s);
      consider(e);
    }
  }
}

// U and W of target leaf b: the coarse adjacent leaves, then the descent of the colleagues
// (B itself included: a leaf with possibly sources).
template <class Images>
void leaf_u_w(const Octree &tree, const InteractionLists &lists, int b, const Rows &coarse_adj, Rows &U, Rows &W)
{
  const auto &cells = tree.cells;
  const Cell &B = cells[b];
  auto &u = U[b];
  for (const Entry &a : coarse_adj[b]) u.push_back(a);
  std::vector<Entry> stack;
  for (int s = 0; s < 27; ++s) {
    const int c = lists.colleagues[b][s];
    if (c < 0 || cells[c].gsrc == 0) continue;
    Entry e{c, {0, 0, 0}};
    Images::shift(B, s, e.s);
    if (cells[c].leaf()) u.push_back(e);
    else stack.push_back(e);
  }
  while (!stack.empty()) {
    const Entry e = stack.back();
    stack.pop_back();
    const Cell &C = cells[e.cell];
    for (int k = 0; k < C.n_children; ++k) {
      const Entry d{C.first_child + k, {e.s[0], e.s[1], e.s[2]}};
      const Cell &D = cells[d.cell];
      if (D.gsrc == 0) continue;
      if (!Images::adjacent(D, d.s, B)) W[b].push_back(d);
      else if (D.leaf()) u.push_back(d);
      else stack.push_back(d);
    }
  }
}

}    // namespace

template <class Images> void build_lists(const Octree &tree, InteractionLists &lists, ImageLists *images)
{
  if (!Images::kImages) images = nullptr;
  const auto &cells = tree.cells;
  const int n = (int) cells.size();
  lists.colleagues.assign(n, {});
  for (auto &c : lists.colleagues) c.fill(-1);
  Rows U(n), V(n), W(n), X(n);
  Rows coarse_adj(n);    // leaves with sources, coarser than B, adjacent to B
  if (n == 0) return;
  Images::root_colleagues(lists.colleagues[0]);

  const int nlev = (int) tree.level_begin.size() - 1;
  for (int l = 1; l < nlev; ++l) {
#pragma omp parallel for schedule(dynamic, 16) if (tree.level_begin[l + 1] - tree.level_begin[l] > 512)
    for (int b = tree.level_begin[l]; b < tree.level_begin[l + 1]; ++b)
      colleagues_v_x<Images>(tree, lists, b, V, X, coarse_adj);
  }
#pragma omp parallel for schedule(dynamic, 16) if (tree.leaves.size() > 512)
  for (int li = 0; li < (int) tree.leaves.size(); ++li) {
    const int b = tree.leaves[li];
    if (cells[b].n_trg() > 0) leaf_u_w<Images>(tree, lists, b, coarse_adj, U, W);
  }
  split(U, lists.U, images ? &images->U : nullptr, true);
  split(W, lists.W, images ? &images->W : nullptr, true);
  split(X, lists.X, images ? &images->X : nullptr, false);
  // V: all entries in the plain list (M2L takes the geometry from the colleague slot)
  split(V, lists.V, nullptr, false);
  if (images) {
    images->V_shift.clear();
    for (int i = 0; i < n; ++i)
      for (const Entry &e : V[i]) images->V_shift.insert(images->V_shift.end(), e.s, e.s + 3);
  }
}

template void build_lists<OpenImages>(const Octree &, InteractionLists &, ImageLists *);
template void build_lists<PeriodicImages>(const Octree &, InteractionLists &, ImageLists *);

void build_interaction_lists(const Octree &tree, InteractionLists &lists)
{
  build_lists<OpenImages>(tree, lists, nullptr);
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
