// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "octree.h"

#include "morton.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kifmm {

void Octree::center(const Cell &c, double out[3]) const
{
  const double h = half_width(c.level);
  const int a[3] = {c.ix, c.iy, c.iz};
  for (int d = 0; d < 3; ++d) out[d] = root.center[d] + root.shape[d] * ((2 * a[d] + 1) * h - root.half_width);
}

std::size_t Octree::bytes() const
{
  return cells.capacity() * sizeof(Cell) + (level_begin.capacity() + leaves.capacity()) * sizeof(int) +
      (src_order.capacity() + trg_order.capacity()) * sizeof(uint32_t);
}

RootBox bounding_cube(std::size_t n_src, const double *src_xyz, std::size_t n_trg, const double *trg_xyz)
{
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::numeric_limits<double>::max();
    hi[d] = -std::numeric_limits<double>::max();
  }
  auto scan = [&](std::size_t n, const double *x) {
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], x[3 * i + d]);
        hi[d] = std::max(hi[d], x[3 * i + d]);
      }
  };
  scan(n_src, src_xyz);
  scan(n_trg, trg_xyz);
  if (n_src + n_trg == 0) return RootBox();
  return bounding_cube_of(lo, hi);
}

RootBox bounding_cube_of(const double lo[3], const double hi[3])
{
  RootBox box;
  double w = 0;
  for (int d = 0; d < 3; ++d) {
    box.center[d] = 0.5 * (lo[d] + hi[d]);
    w = std::max(w, 0.5 * (hi[d] - lo[d]));
  }
  double scale = 0;
  for (int d = 0; d < 3; ++d) scale = std::max(scale, std::fabs(box.center[d]));
  // enlarge so that every point maps strictly inside; a degenerate set gets a unit box
  w = w * (1.0 + 1e-8) + 1e-12 * scale;
  box.half_width = w > 0 ? w : 1.0;
  return box;
}

RootBox evaluation_root(bool fixed, const double fixed_center[3], double fixed_half_width,
                        const double *fixed_shape, bool size_dependent_operators, std::size_t n_src, const double *src_xyz,
                        std::size_t n_trg, const double *trg_xyz)
{
  RootBox root;
  if (fixed) {
    for (int d = 0; d < 3; ++d) root.center[d] = fixed_center[d];
    root.half_width = fixed_half_width;
    if (fixed_shape)
      for (int d = 0; d < 3; ++d) root.shape[d] = fixed_shape[d];
    return root;
  }
  root = bounding_cube(n_src, src_xyz, n_trg, trg_xyz);
  if (size_dependent_operators) root.half_width = std::exp2(std::ceil(std::log2(root.half_width)));
  return root;
}

void morton_keys(const RootBox &root, std::size_t n, const double *xyz, std::vector<uint64_t> &keys)
{
  keys.resize(n);
  const double nmax = double(1u << kMortonBits);
  double lo[3], inv[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = root.center[d] - root.half_width * root.shape[d];
    inv[d] = nmax / (2.0 * root.half_width * root.shape[d]);
  }
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    uint32_t a[3];
    for (int d = 0; d < 3; ++d) {
      double u = std::floor((xyz[3 * i + d] - lo[d]) * inv[d]);
      u = std::min(std::max(u, 0.0), nmax - 1);
      a[d] = (uint32_t) u;
    }
    keys[i] = morton_encode(a[0], a[1], a[2]);
  }
}

void radix_sort_keys(std::vector<uint64_t> &keys, std::vector<uint32_t> &order)
{
  const std::size_t n = keys.size();
  order.resize(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = (uint32_t) i;
  if (n < 2) return;
  if (n < 256) {
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
    std::vector<uint64_t> k2(n);
    for (std::size_t i = 0; i < n; ++i) k2[i] = keys[order[i]];
    keys.swap(k2);
    return;
  }
  constexpr int kBits = 11, kBuckets = 1 << kBits;
  std::vector<uint64_t> kbuf(n);
  std::vector<uint32_t> obuf(n);
  std::vector<std::size_t> count(kBuckets);
  uint64_t all_or = 0, all_and = ~uint64_t(0);
  for (uint64_t k : keys) {
    all_or |= k;
    all_and &= k;
  }
  const uint64_t varying = all_or ^ all_and;
  for (int shift = 0; shift < 64; shift += kBits) {
    if (((varying >> shift) & (kBuckets - 1)) == 0) continue;    // digit constant: skip pass
    std::fill(count.begin(), count.end(), 0);
    for (std::size_t i = 0; i < n; ++i) ++count[(keys[i] >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (int b = 0; b < kBuckets; ++b) {
      const std::size_t c = count[b];
      count[b] = sum;
      sum += c;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t pos = count[(keys[i] >> shift) & (kBuckets - 1)]++;
      kbuf[pos] = keys[i];
      obuf[pos] = order[i];
    }
    keys.swap(kbuf);
    order.swap(obuf);
  }
}

bool cells_adjacent(const Cell &a0, const Cell &b0)
{
  const Cell &a = a0.level <= b0.level ? a0 : b0;    // a coarser
  const Cell &b = a0.level <= b0.level ? b0 : a0;
  const int64_t s = int64_t(1) << (b.level - a.level);
  const int64_t ax[3] = {a.ix, a.iy, a.iz}, bx[3] = {b.ix, b.iy, b.iz};
  for (int d = 0; d < 3; ++d) {
    const int64_t lo = ax[d] * s, hi = (ax[d] + 1) * s;
    if (bx[d] + 1 < lo || bx[d] > hi) return false;
  }
  return true;
}

bool cells_adjacent_shifted(const Cell &a, const signed char sa[3], const Cell &b)
{
  const int lf = std::max(a.level, b.level);
  const int64_t ka = int64_t(1) << (lf - a.level), kb = int64_t(1) << (lf - b.level);
  const int64_t period = int64_t(1) << lf;
  const int64_t ax[3] = {a.ix, a.iy, a.iz}, bx[3] = {b.ix, b.iy, b.iz};
  for (int d = 0; d < 3; ++d) {
    const int64_t alo = ax[d] * ka + sa[d] * period, ahi = alo + ka;
    const int64_t blo = bx[d] * kb, bhi = blo + kb;
    if (alo > bhi || blo > ahi) return false;
  }
  return true;
}

namespace {

// Stable partition of keys[b..e) (and the parallel index array) into the 8 octants of the
// digit at `shift`; counts[oct] receives the octant sizes.
void partition_octants(uint64_t *keys, uint32_t *idx, uint32_t b, uint32_t e, int shift, uint32_t counts[8],
                       std::vector<uint64_t> &tk, std::vector<uint32_t> &ti)
{
  for (int o = 0; o < 8; ++o) counts[o] = 0;
  for (uint32_t i = b; i < e; ++i) ++counts[(keys[i] >> shift) & 7];
  uint32_t pos[8], sum = 0;
  for (int o = 0; o < 8; ++o) {
    pos[o] = sum;
    sum += counts[o];
  }
  tk.resize(e - b);
  ti.resize(e - b);
  for (uint32_t i = b; i < e; ++i) {
    const uint32_t p = pos[(keys[i] >> shift) & 7]++;
    tk[p] = keys[i];
    ti[p] = idx[i];
  }
  std::copy(tk.begin(), tk.end(), keys + b);
  std::copy(ti.begin(), ti.end(), idx + b);
}

}    // namespace

// Top-down build: a cell that must split has its source and target ranges partitioned by
// the next 3-bit Morton digit (an MSD radix sort that stops at the leaves); partitions of the
// cells of one level run in parallel (disjoint ranges), children are appended in cell order.
// Points end up ordered by leaf in Morton order (input order inside a leaf).
void build_octree(Octree &tree, const RootBox &root, std::size_t n_src, const double *src_xyz,
                  std::size_t n_trg, const double *trg_xyz, int leaf_size, int max_depth, const TopTree *top)
{
  tree.root = root;
  tree.cells.clear();
  tree.level_begin.clear();
  tree.leaves.clear();
  tree.top_index.clear();
  if (top) tree.top_index.push_back(0);
  leaf_size = std::max(leaf_size, 1);
  max_depth = std::min(std::max(max_depth, 0), kMortonBits);
  const bool same = src_xyz == trg_xyz && n_src == n_trg;    // one set: partition once

  std::vector<uint64_t> skeys, tkeys;
  morton_keys(root, n_src, src_xyz, skeys);
  if (!same) morton_keys(root, n_trg, trg_xyz, tkeys);
  tree.src_order.resize(n_src);
  tree.trg_order.resize(n_trg);
  for (std::size_t i = 0; i < n_src; ++i) tree.src_order[i] = (uint32_t) i;
  for (std::size_t i = 0; i < n_trg; ++i) tree.trg_order[i] = (uint32_t) i;

  Cell rc;
  rc.src_end = (uint32_t) n_src;
  rc.trg_end = (uint32_t) n_trg;
  rc.gsrc = (uint32_t) n_src;
  rc.gtrg = (uint32_t) n_trg;
  if (top) {
    rc.gsrc = top->cells[0].gsrc;
    rc.gtrg = top->cells[0].gtrg;
  }
  tree.cells.push_back(rc);
  tree.level_begin.push_back(0);
  std::vector<uint32_t> counts;    // per cell of the level: 8 source + 8 target octant sizes
  std::vector<char> split;
  int level = 0;
  for (;;) {
    const int begin = tree.level_begin[level], end = (int) tree.cells.size(), n = end - begin;
    counts.assign((std::size_t) n * 16, 0);
    split.assign(n, 0);
    std::size_t work = 0;
    for (int ci = begin; ci < end; ++ci) {
      Cell &c = tree.cells[ci];
      const int t = top ? tree.top_index[ci] : -1;
      if (t >= 0 && top->cells[t].n_children > 0) split[ci - begin] = 1;    // copy of the top tree
      else if (t >= 0) {                                                      // frontier cell
        const bool open = top->open[t] != 0, here = c.n_src() + c.n_trg() > 0;
        split[ci - begin] = open && here;
        c.pruned = open && !here;
      } else
        split[ci - begin] = level < max_depth && ((int) c.n_src() > leaf_size || (int) c.n_trg() > leaf_size);
      if (split[ci - begin]) work += c.n_src() + c.n_trg();
    }
    const int shift = 3 * (kMortonBits - level - 1);
#pragma omp parallel if (work > 20000)
    {
      std::vector<uint64_t> tk;
      std::vector<uint32_t> ti;
#pragma omp for schedule(dynamic, 1)
      for (int ci = begin; ci < end; ++ci) {
        if (!split[ci - begin]) continue;
        const Cell &c = tree.cells[ci];
        uint32_t *cnt = &counts[(std::size_t) (ci - begin) * 16];
        partition_octants(skeys.data(), tree.src_order.data(), c.src_begin, c.src_end, shift, cnt, tk, ti);
        if (!same) partition_octants(tkeys.data(), tree.trg_order.data(), c.trg_begin, c.trg_end, shift, cnt + 8, tk, ti);
        else
          for (int o = 0; o < 8; ++o) cnt[8 + o] = cnt[o];
      }
    }
    for (int ci = begin; ci < end; ++ci) {
      if (!split[ci - begin]) {
        if (!tree.cells[ci].pruned) tree.leaves.push_back(ci);
        continue;
      }
      const Cell c = tree.cells[ci];
      const uint32_t *cnt = &counts[(std::size_t) (ci - begin) * 16];
      uint32_t sp = c.src_begin, tp = c.trg_begin;
      const int first = (int) tree.cells.size();
      int nch = 0;
      for (int oct = 0; oct < 8; ++oct) {
        const uint32_t se = sp + cnt[oct], te = tp + cnt[8 + oct];
        const int t = top ? tree.top_index[ci] : -1;
        const bool forced = t >= 0 && top->cells[t].n_children > 0;
        const int top_child = forced ? top->cells[t].child[oct] : -1;
        if (forced ? top_child >= 0 : (se > sp || te > tp)) {
          Cell ch = child_cell(c, ci, oct);
          ch.src_begin = sp;
          ch.src_end = se;
          ch.trg_begin = tp;
          ch.trg_end = te;
          ch.gsrc = se - sp;
          ch.gtrg = te - tp;
          if (top) tree.top_index.push_back(top_child);
          if (top_child >= 0) {    // a top cell: the global counts
            ch.gsrc = top->cells[top_child].gsrc;
            ch.gtrg = top->cells[top_child].gtrg;
          }
          tree.cells[ci].child[oct] = (int) tree.cells.size();
          tree.cells.push_back(ch);
          ++nch;
        }
        sp = se;
        tp = te;
      }
      tree.cells[ci].first_child = first;
      tree.cells[ci].n_children = nch;
    }
    tree.level_begin.push_back((int) tree.cells.size() > end ? end : end);
    if ((int) tree.cells.size() == end) break;
    ++level;
  }
  if (same) tree.trg_order = tree.src_order;
  tree.depth = (int) tree.level_begin.size() - 2;
}

}    // namespace kifmm
