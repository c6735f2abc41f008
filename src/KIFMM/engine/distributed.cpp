// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "distributed.h"

#include "morton.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace kifmm {

int choose_top_level(uint64_t npoints, int nranks, int nsurf, int max_depth, int leaf_size)
{
  const int hi = std::max(0, std::min(5, max_depth));
  int best = std::min(2, hi);
  double best_cost = std::numeric_limits<double>::max();
  const double per_rank = (double) npoints / std::max(nranks, 1), side = std::cbrt((double) std::max(nranks, 1));
  // frontier cells: at most 8^L, and no more than about the leaves of the whole tree
  const double leaves = 2.0 * (double) npoints / std::max(leaf_size, 1) + 1.0;
  for (int l = std::min(2, hi); l <= hi; ++l) {
    const double r = side / std::exp2(l), halo = std::pow(1.0 + 2.0 * r, 3) - 1.0;
    const double ghosts = nranks > 1 ? per_rank * halo : 0.0;
    const double cost = ghosts * (32.0 + kGhostWork) + 8.0 * nsurf * std::min(std::exp2(3 * l), leaves);
    if (cost < best_cost) {
      best_cost = cost;
      best = l;
    }
  }
  return best;
}

void keep_targets(Octree &tree, std::size_t n_keep)
{
  const std::size_t n = tree.trg_order.size();
  std::vector<uint32_t> before(n + 1, 0), order;
  order.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const bool keep = tree.trg_order[i] < n_keep;
    before[i + 1] = before[i] + keep;
    if (keep) order.push_back(tree.trg_order[i]);
  }
  for (Cell &c : tree.cells) {
    c.trg_begin = before[c.trg_begin];
    c.trg_end = before[c.trg_end];
  }
  tree.trg_order.swap(order);
}

namespace {

struct Timer {
  double &acc;
  double t0;
  explicit Timer(double &a) : acc(a), t0(omp_get_wtime()) {}
  ~Timer() { acc += omp_get_wtime() - t0; }
};

// root shifts under which cells can be neighbours: none (open), or the 27 images of the
// periodic cell (a cell and an image of it at shift n, n in {-1,0,1}^3)
struct Shifts {
  std::vector<std::array<signed char, 3>> s;
  explicit Shifts(bool periodic)
  {
    const int r = periodic ? 1 : 0;
    for (int x = -r; x <= r; ++x)
      for (int y = -r; y <= r; ++y)
        for (int z = -r; z <= r; ++z) s.push_back({(signed char) x, (signed char) y, (signed char) z});
  }
};

// frontier cells (top cells without children) touching cell x, some image of them with
// periodic shifts: descend the top tree once per shift
template <class F> void touching(const TopTree &top, const Shifts &shifts, const Cell &x, F &&visit)
{
  std::vector<int> stack;
  for (const auto &sh : shifts.s) {
    stack.assign(1, 0);
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      const Cell &C = top.cells[c];
      if (!cells_adjacent_shifted(C, sh.data(), x)) continue;
      if (C.n_children == 0) visit(c);
      else
        for (int k = 0; k < C.n_children; ++k) stack.push_back(C.first_child + k);
    }
  }
}

// frontier cells below (or equal to) top cell c
template <class F> void below(const TopTree &top, int c, F &&visit)
{
  std::vector<int> stack{c};
  while (!stack.empty()) {
    const int a = stack.back();
    stack.pop_back();
    const Cell &A = top.cells[a];
    if (A.n_children == 0) visit(a);
    else
      for (int k = 0; k < A.n_children; ++k) stack.push_back(A.first_child + k);
  }
}

}    // namespace

void global_bounds(Communicator &comm, std::size_t n, const double *xyz, double lo[3], double hi[3])
{
  double b[6];    // the minima of x, y, z, -x, -y, -z
  for (int d = 0; d < 6; ++d) b[d] = std::numeric_limits<double>::max();
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      b[d] = std::min(b[d], xyz[3 * i + d]);
      b[3 + d] = std::min(b[3 + d], -xyz[3 * i + d]);
    }
  comm.allreduce_min(b, 6);
  for (int d = 0; d < 3; ++d) lo[d] = b[d], hi[d] = -b[3 + d];
}

namespace {

// Global root and counts (reductions); false when there are no points or no sources.
bool global_root(Communicator &comm, const DistributedConfig &cfg, const LocalPoints &pts, DistributedData &out)
{
  const std::size_t n = pts.n;
  // root: bounding cube of all points (every point is a target), as bounding_cube()
  double lo[3], hi[3];
  uint64_t cnt[2] = {n, 0};
  for (std::size_t i = 0; i < n; ++i) cnt[1] += pts.source(i);
  {
    Timer t(out.t_comm);
    global_bounds(comm, n, pts.xyz, lo, hi);
    comm.allreduce_sum(cnt, 2);
  }
  out.global_points = cnt[0];
  out.global_sources = cnt[1];
  if (cnt[0] == 0 || cnt[1] == 0) return false;
  if (cfg.fixed_root) out.root = *cfg.fixed_root;
  else {
    out.root = bounding_cube_of(lo, hi);
    if (cfg.pow2_root) out.root.half_width = std::exp2(std::ceil(std::log2(out.root.half_width)));
  }
  return true;
}

// Children of the top cells `refine` (one level) from the global counts per octant (one
// reduction); the points' top cells `at` move to the children; returns the new cells.
std::vector<int> refine_top_level(Communicator &comm, const LocalPoints &pts, const std::vector<uint64_t> &keys,
                                  const std::vector<int> &refine, std::vector<int> &at, DistributedData &out)
{
  TopTree &top = out.top;
  std::vector<int> slot(top.cells.size(), -1), current;
  for (std::size_t k = 0; k < refine.size(); ++k) slot[refine[k]] = (int) k;
  const int level = top.cells[refine[0]].level;    // all cells of `current` share a level
  const int shift = 3 * (kMortonBits - level - 1);
  std::vector<uint64_t> counts(16 * refine.size(), 0);
  for (std::size_t i = 0; i < pts.n; ++i) {
    const int k = slot[at[i]];
    if (k < 0) continue;
    const int oct = (int) ((keys[i] >> shift) & 7);
    counts[16 * (std::size_t) k + oct] += pts.source(i);
    ++counts[16 * (std::size_t) k + 8 + oct];
  }
  {
    Timer t(out.t_comm);
    comm.allreduce_sum(counts.data(), counts.size());
  }
  for (std::size_t k = 0; k < refine.size(); ++k) {
    const int c = refine[k];
    const int first = (int) top.cells.size();
    int nch = 0;
    for (int oct = 0; oct < 8; ++oct) {
      const uint64_t s = counts[16 * k + oct], t = counts[16 * k + 8 + oct];
      if (s + t == 0) continue;
      Cell ch = child_cell(top.cells[c], c, oct);
      ch.gsrc = (uint32_t) s;
      ch.gtrg = (uint32_t) t;
      top.cells[c].child[oct] = (int) top.cells.size();
      current.push_back((int) top.cells.size());
      top.cells.push_back(ch);
      ++nch;
    }
    top.cells[c].first_child = first;
    top.cells[c].n_children = nch;
  }
  for (std::size_t i = 0; i < pts.n; ++i) {
    const int k = slot[at[i]];
    if (k >= 0) at[i] = top.cells[at[i]].child[(keys[i] >> shift) & 7];
  }
  return current;
}

// Top tree: the global tree refined from the root, level by level (one reduction of the
// children's counts per level), while a cell splits in the global tree and holds more than
// 2 N / 8^L points, L from choose_top_level: about 8^L frontier cells for uniform points,
// finer where the points are dense, so that no frontier cell holds much more than 2 N / 8^L
// points. Its size depends on L (on P), not on N. at: the frontier cell of every point.
void build_top_tree(Communicator &comm, const DistributedConfig &cfg, const LocalPoints &pts, DistributedData &out,
                    std::vector<int> &at)
{
  const int leaf_size = cfg.leaf_size, max_depth = cfg.max_depth, top_level = cfg.top_level;
  const uint64_t npoints = out.global_points;
  const int L = std::min(top_level > 0 ? top_level : choose_top_level(npoints, comm.size(), cfg.nsurf, max_depth, leaf_size),
                         max_depth);
  const double refine_above = std::max((double) leaf_size, 2.0 * (double) npoints / std::exp2(3 * L));
  const int deepest = std::min(max_depth, top_level > 0 ? L : L + 8);
  std::vector<uint64_t> keys;
  morton_keys(out.root, pts.n, pts.xyz, keys);
  TopTree &top = out.top;
  {
    Cell rc;
    rc.gsrc = (uint32_t) out.global_sources;
    rc.gtrg = (uint32_t) npoints;
    top.cells.assign(1, rc);
  }
  at.assign(pts.n, 0);
  std::vector<int> current{0}, refine;
  while (!current.empty()) {
    refine.clear();
    for (int c : current) {
      const Cell &C = top.cells[c];
      const bool split = C.level < max_depth && ((int) C.gsrc > leaf_size || (int) C.gtrg > leaf_size);
      const bool deeper = top_level > 0 ? C.level < L : (C.level < deepest && (C.level < 2 || C.gtrg > refine_above));
      if (split && deeper) refine.push_back(c);
    }
    if (refine.empty()) break;
    current = refine_top_level(comm, pts, keys, refine, at, out);
  }
  const int ntop = (int) top.cells.size();
  top.open.assign(ntop, 0);
  top.top_level = 0;
  for (int c = 0; c < ntop; ++c) {
    const Cell &C = top.cells[c];
    top.top_level = std::max(top.top_level, C.level);
    top.open[c] = C.n_children == 0 && C.level < max_depth && ((int) C.gsrc > leaf_size || (int) C.gtrg > leaf_size);
  }
  // frontier cells (top cells without children)
  out.frontier_index.assign(ntop, -1);
  for (int c = 0; c < ntop; ++c)
    if (top.cells[c].n_children == 0) {
      out.frontier_index[c] = (int) out.frontier.size();
      out.frontier.push_back(c);
    }
  out.n_top_global = ntop;
  out.top_internal.assign(ntop, 0);
  for (int c = 0; c < ntop; ++c) out.top_internal[c] = top.cells[c].n_children > 0;
}

// This rank's points by frontier cell and the ranks that hold points of every frontier cell.
struct FrontierOccupancy {
  std::vector<int> fstart, fpoints;    // own points of frontier cell f: fpoints[fstart[f] .. fstart[f+1])
  std::vector<int> mine;               // frontier cells this rank holds points of
  std::vector<int> ostart, occ;        // ranks holding points of f: occ[ostart[f] .. ostart[f+1]), increasing
};

FrontierOccupancy frontier_occupancy(Communicator &comm, const LocalPoints &pts, const std::vector<int> &at,
                                     DistributedData &out)
{
  const int nranks = comm.size(), me = comm.rank();
  const int nf = (int) out.frontier.size();
  const std::vector<int> &findex = out.frontier_index;
  FrontierOccupancy o;
  // counting sort, input order inside a cell
  o.fstart.assign(nf + 1, 0);
  o.fpoints.resize(pts.n);
  for (std::size_t i = 0; i < pts.n; ++i) ++o.fstart[findex[at[i]] + 1];
  for (int f = 0; f < nf; ++f) o.fstart[f + 1] += o.fstart[f];
  {
    std::vector<int> pos(o.fstart.begin(), o.fstart.end() - 1);
    for (std::size_t i = 0; i < pts.n; ++i) o.fpoints[pos[findex[at[i]]]++] = (int) i;
  }
  std::vector<int> all, per_rank;
  for (int f = 0; f < nf; ++f)
    if (o.fstart[f + 1] > o.fstart[f]) o.mine.push_back(f);
  {
    Timer t(out.t_comm);
    comm.allgatherv(o.mine, all, per_rank);
  }
  o.ostart.assign(nf + 1, 0);
  o.occ.resize(all.size());
  for (int f : all) ++o.ostart[f + 1];
  for (int f = 0; f < nf; ++f) o.ostart[f + 1] += o.ostart[f];
  {
    std::vector<int> pos(o.ostart.begin(), o.ostart.end() - 1);
    std::size_t k = 0;
    for (int r = 0; r < nranks; ++r)
      for (int j = 0; j < per_rank[r]; ++j) o.occ[pos[all[k++]]++] = r;
  }
  out.responsible.assign(nf, 0);
  for (int f = 0; f < nf; ++f) out.responsible[f] = o.ostart[f + 1] > o.ostart[f] && o.occ[o.ostart[f]] == me;
  out.occupied.assign(nf, 0);
  for (int f : o.mine) out.occupied[f] = 1;
  return o;
}

enum : char { kNone = 0, kLet = 1, kWhole = 2 };

// Frontier cells whose points this rank needs (doc/design.md: rules i-iii); periodic: the
// neighbours through the cell's faces too (images). How: kWhole, all points from every rank
// holding some (the cells this rank holds points of, global leaves, and the small subtrees of
// rule iii); kLet, the other open cells: the part of their subtree this rank's lists reach,
// from the responsible rank (exchange_let).
std::vector<char> needed_frontier_cells(const DistributedConfig &cfg, const std::vector<int> &mine,
                                        const DistributedData &out)
{
  const TopTree &top = out.top;
  const int ntop = out.n_top_global;
  const std::vector<int> &findex = out.frontier_index;
  const Shifts shifts(cfg.periodic);
  std::vector<char> need(out.frontier.size(), kNone), own_top(ntop, 0);
  auto mark = [&](int c) { need[findex[c]] = std::max<char>(need[findex[c]], kLet); };
  auto mark_whole = [&](int c) { need[findex[c]] = kWhole; };
  for (int f : mine) {
    int c = out.frontier[f];
    touching(top, shifts, top.cells[c], mark);    // (i)
    for (; c >= 0 && !own_top[c]; c = top.cells[c].parent) own_top[c] = 1;
  }
  for (int c = 1; c < ntop; ++c) {    // (ii) coarser top leaves touching parent(C)
    if (!own_top[c]) continue;
    const Cell &C = top.cells[c];
    touching(top, shifts, top.cells[C.parent], [&](int a) {
      if (top.cells[a].level < C.level) mark(a);
    });
  }
  // (iii) top cells A whose parent touches an own frontier cell C_f, finer than C_f, not touching
  // it, with at most nsurf sources: W lists of leaves in C_f take their particles (direct sum)
  // (periodic: per image of the top tree, A and its children under the same shift)
  std::vector<int> st;
  for (int f : mine) {
    const Cell &B = top.cells[out.frontier[f]];
    for (const auto &sh : shifts.s) {
      st.assign(1, 0);
      while (!st.empty()) {
        const int a = st.back();
        st.pop_back();
        const Cell &A = top.cells[a];
        if (!cells_adjacent_shifted(A, sh.data(), B)) continue;
        for (int k = 0; k < A.n_children; ++k) {
          const int d = A.first_child + k;
          const Cell &D = top.cells[d];
          if (D.gsrc == 0) continue;
          if (cells_adjacent_shifted(D, sh.data(), B)) st.push_back(d);
          else if (D.level > B.level && (int) D.gsrc <= cfg.nsurf) below(top, d, mark_whole);
        }
      }
    }
  }
  return need;
}

// Requests: whole cells from each rank that holds points there; LETs later (exchange_let), from
// the responsible rank (a cell this rank holds points of and is responsible for comes whole;
// where another rank is responsible, that rank imports this rank's points of it and sends the
// LET of the rest). The whole cells' points are imported here (ghosts after the own points).
void import_whole_cells(Communicator &comm, const LocalPoints &pts, const FrontierOccupancy &o,
                        std::vector<char> &need, DistributedData &out)
{
  const int nranks = comm.size(), me = comm.rank();
  const int nf = (int) out.frontier.size();
  const std::size_t n = pts.n;
  const double *xyz = pts.xyz, *q = pts.q;
  for (int f = 0; f < nf; ++f)
    if (need[f] == kLet && (out.responsible[f] || !out.top.open[out.frontier[f]])) need[f] = kWhole;
  out.complete.assign(nf, 0);
  for (int f = 0; f < nf; ++f) out.complete[f] = need[f] == kWhole;
  std::vector<std::vector<int>> req(nranks), got;
  out.let_from.assign(nranks, {});
  for (int f = 0; f < nf; ++f) {
    if (need[f] == kWhole)
      for (int k = o.ostart[f]; k < o.ostart[f + 1]; ++k)
        if (o.occ[k] != me) req[o.occ[k]].push_back(f);
    if (need[f] == kLet && o.ostart[f + 1] > o.ostart[f]) out.let_from[o.occ[o.ostart[f]]].push_back(f);
  }
  uint64_t lets = 0;    // LETs this rank needs; summed: whether exchange_let runs at all
  for (const auto &v : out.let_from) lets += v.size();
  {
    Timer t(out.t_comm);
    comm.alltoallv(req, got);
    comm.allreduce_sum(&lets, 1);
  }
  out.any_let = lets > 0;
  std::vector<std::vector<double>> send(nranks), recv;
  for (int r = 0; r < nranks; ++r)
    for (int f : got[r]) {
      for (int k = o.fstart[f]; k < o.fstart[f + 1]; ++k) {
        const int i = o.fpoints[k];
        pack_point(send[r], xyz, q, pts.moments ? pts.mu : nullptr, i);
      }
    }
  for (int r = 0; r < nranks; ++r) out.ghost_bytes += sizeof(double) * send[r].size();
  {
    Timer t(out.t_comm);
    comm.alltoallv(send, recv);
  }
  const bool moments = pts.moments;
  const std::size_t w = point_record_size(moments);
  std::size_t nghost = 0;
  out.ghost_from.assign(nranks + 1, 0);
  for (int r = 0; r < nranks; ++r) out.ghost_from[r + 1] = out.ghost_from[r] + recv[r].size() / w;
  for (const auto &v : recv) nghost += v.size() / w;
  out.n_own = n;
  out.xyz.assign(xyz, xyz + 3 * n);
  out.q.assign(q, q + n);
  out.mu.clear();
  if (moments) out.mu.assign(pts.mu, pts.mu + 3 * n);
  out.xyz.reserve(3 * (n + nghost));
  out.q.reserve(n + nghost);
  if (moments) out.mu.reserve(3 * (n + nghost));
  for (const auto &v : recv)
    for (std::size_t j = 0; j + w <= v.size(); j += w) unpack_point(&v[j], moments, out.xyz, out.q, out.mu);
}

}    // namespace

void distributed_setup(Communicator &comm, const DistributedConfig &config, const LocalPoints &pts,
                       DistributedData &out)
{
  out = DistributedData();
  out.moments = pts.moments;
  DistributedConfig cfg = config;
  cfg.leaf_size = std::max(cfg.leaf_size, 1);
  cfg.max_depth = std::min(std::max(cfg.max_depth, 0), kMortonBits);
  if (!global_root(comm, cfg, pts, out)) return;
  std::vector<int> at;    // top cell of every point (its frontier cell)
  build_top_tree(comm, cfg, pts, out, at);
  const FrontierOccupancy occupancy = frontier_occupancy(comm, pts, at, out);
  std::vector<char> need = needed_frontier_cells(cfg, occupancy.mine, out);
  import_whole_cells(comm, pts, occupancy, need, out);
}

namespace {

// closed cells a and b touch or overlap (periodic: some image of a)
bool touch(const Cell &a, const Cell &b, const Shifts &shifts)
{
  for (const auto &sh : shifts.s)
    if (cells_adjacent_shifted(a, sh.data(), b)) return true;
  return false;
}

// A cell of the asking rank's tree that holds its own points (a target cell of its lists), or
// (coarse) a frontier cell of its points that it does not hold completely, standing for the
// unknown cells of its points inside: like a leaf, but its W-list partners may touch it.
struct AskingCell {
  Cell cell;
  bool leaf, coarse;
};

// Fragment of the LET of tree cell cf for one asking rank (its cells touching cf):
// [ncells, npoints, ncells x (parent, octant, gsrc, gtrg, kind, has_density), densities, points]
// with parent = index in the fragment (-1: cf itself), kind 0 leaf, 1 children follow, 2 split
// in the global tree but children not sent.
void let_fragment(const Octree &tree, int cf, const std::vector<AskingCell> &asking, const Shifts &shifts,
                  const std::vector<double> &up, int nsurf, const DistributedData &dd, std::size_t skip_begin,
                  std::size_t skip_end, std::vector<double> &out)
{
  const auto &cells = tree.cells;
  auto children_needed = [&](const Cell &p) {    // colleagues, V lists, descent of U/W
    for (const AskingCell &y : asking)
      if ((y.leaf || y.coarse ? y.cell.level <= p.level : y.cell.level == p.level) && touch(p, y.cell, shifts))
        return true;
    return false;
  };
  auto points_needed = [&](const Cell &d) {    // leaves: U (own leaf) and X (parent of an own leaf)
    for (const AskingCell &y : asking)
      if ((y.leaf || y.coarse || y.cell.level >= d.level) && touch(d, y.cell, shifts)) return true;
    return false;
  };
  auto w_direct = [&](const Cell &a, const Cell &parent) {    // a in W(B) of an own leaf B, direct
    if (a.gsrc == 0 || (int) a.gsrc > nsurf) return false;
    for (const AskingCell &y : asking)
      if ((y.leaf || y.coarse) && y.cell.level < a.level && touch(parent, y.cell, shifts) &&
          (y.coarse || !touch(a, y.cell, shifts)))
        return true;
    return false;
  };
  std::vector<int> emitted, parent_slot, kind;
  std::vector<char> density;
  std::vector<std::pair<uint32_t, uint32_t>> ranges;    // target ranges whose points are sent
  std::vector<int> queue, slot_of;                      // cells whose children are sent
  if (children_needed(cells[cf])) {
    queue.push_back(cf);
    slot_of.push_back(-1);
  }
  for (std::size_t qi = 0; qi < queue.size(); ++qi) {
    const Cell &P = cells[queue[qi]];
    for (int k = 0; k < P.n_children; ++k) {
      const int d = P.first_child + k;
      const Cell &D = cells[d];
      int kd = 0;
      if (!D.leaf()) {
        kd = children_needed(D) ? 1 : 2;
        if (kd == 1) {
          queue.push_back(d);
          slot_of.push_back((int) emitted.size());
        }
      }
      emitted.push_back(d);
      parent_slot.push_back(slot_of[qi]);
      kind.push_back(kd);
      // points instead of the density where they take fewer bytes (the asking rank computes
      // the density from them: all points of the cell, so its subtree is the global one)
      const bool by_points = D.gsrc > 0 && point_record_size(dd.moments) * D.gtrg < (std::size_t) nsurf;
      density.push_back(D.gsrc > 0 && !by_points);
      if (by_points || (D.leaf() && points_needed(D)) || w_direct(D, P)) ranges.emplace_back(D.trg_begin, D.trg_end);
    }
  }
  // points of the marked cells once (nested ranges merged)
  std::sort(ranges.begin(), ranges.end());
  std::vector<int> pts;
  uint32_t reach = 0;
  for (const auto &r : ranges) {
    for (uint32_t i = std::max(r.first, reach); i < r.second; ++i)
      if (tree.trg_order[i] < skip_begin || tree.trg_order[i] >= skip_end) pts.push_back((int) tree.trg_order[i]);
    reach = std::max(reach, r.second);
  }
  out.push_back((double) emitted.size());
  out.push_back((double) pts.size());
  for (std::size_t k = 0; k < emitted.size(); ++k) {
    const Cell &D = cells[emitted[k]];
    out.insert(out.end(), {(double) parent_slot[k], (double) (D.prefix & 7), (double) D.gsrc, (double) D.gtrg,
                           (double) kind[k], density[k] ? 1.0 : 0.0});
  }
  for (std::size_t k = 0; k < emitted.size(); ++k)
    if (density[k]) out.insert(out.end(), &up[(std::size_t) emitted[k] * nsurf], &up[(std::size_t) (emitted[k] + 1) * nsurf]);
  for (int i : pts) pack_point(out, dd.xyz.data(), dd.q.data(), dd.moments ? dd.mu.data() : nullptr, (std::size_t) i);
}

}    // namespace

namespace {

// Requests to the responsible ranks of the frontier cells in dd.let_from: per frontier cell F,
// this rank's cells with own points that touch F, [f, count, count x (level, ix, iy, iz, kind)]
// with kind 0 non-leaf, 1 leaf, 2 coarse (an incomplete frontier cell; F itself: the sender knows).
std::vector<std::vector<int>> let_requests(int nranks, const Octree &tree, std::size_t n_own, const Shifts &shifts,
                                           const DistributedData &dd)
{
  const int ntop = dd.n_top_global;
  const auto &cells = tree.cells;
  std::vector<uint32_t> own_before(tree.trg_order.size() + 1, 0);    // own targets before a sorted position
  for (std::size_t i = 0; i < tree.trg_order.size(); ++i) own_before[i + 1] = own_before[i] + (tree.trg_order[i] < n_own);
  auto holds_own = [&](const Cell &c) { return own_before[c.trg_end] > own_before[c.trg_begin]; };
  auto incomplete_frontier = [&](int c) {
    const int t = tree.top_index[c];
    return t >= 0 && t < ntop && dd.frontier_index[t] >= 0 && !dd.complete[dd.frontier_index[t]];
  };
  std::vector<std::vector<int>> req(nranks);
  for (int r = 0; r < nranks; ++r)
    for (int f : dd.let_from[r]) {
      const int top_f = dd.frontier[f];
      const Cell &F = dd.top.cells[top_f];
      std::vector<int> &q = req[r];
      q.push_back(f);
      const std::size_t at = q.size();
      q.push_back(0);
      std::vector<int> stack{0};
      while (!stack.empty()) {
        const int c = stack.back();
        const Cell &C = cells[c];
        stack.pop_back();
        if (!holds_own(C) || !touch(C, F, shifts)) continue;
        if (incomplete_frontier(c)) {
          if (tree.top_index[c] != top_f) {
            q.insert(q.end(), {C.level, C.ix, C.iy, C.iz, 2});
            ++q[at];
          }
          continue;
        }
        q.insert(q.end(), {C.level, C.ix, C.iy, C.iz, C.leaf() ? 1 : 0});
        ++q[at];
        for (int k = 0; k < C.n_children; ++k) stack.push_back(C.first_child + k);
      }
    }
  return req;
}

// Answers to the requests `got` (per asking rank r): [f, fragment] for each cell it asked for.
std::vector<std::vector<double>> let_answers(const Octree &tree, const std::vector<double> &up, int nsurf,
                                             const Shifts &shifts, const std::vector<std::vector<int>> &got,
                                             DistributedData &dd)
{
  const int nranks = (int) got.size(), ntop = dd.n_top_global;
  const auto &cells = tree.cells;
  std::vector<int> local_of(ntop, -1);
  for (std::size_t c = 0; c < cells.size(); ++c)
    if (tree.top_index[c] >= 0 && tree.top_index[c] < ntop) local_of[tree.top_index[c]] = (int) c;
  std::vector<std::vector<double>> send(nranks);
  for (int r = 0; r < nranks; ++r) {
    const std::vector<int> &g = got[r];
    for (std::size_t k = 0; k < g.size();) {
      const int f = g[k], count = g[k + 1];
      k += 2;
      std::vector<AskingCell> asking(count);
      for (int j = 0; j < count; ++j, k += 5) {
        Cell &c = asking[j].cell;
        c.level = g[k];
        c.ix = g[k + 1];
        c.iy = g[k + 2];
        c.iz = g[k + 3];
        asking[j].leaf = g[k + 4] == 1;
        asking[j].coarse = g[k + 4] == 2;
      }
      // the asking rank's own cells inside F: those of its points this rank imported
      const int cf = local_of[dd.frontier[f]];
      const std::size_t from_b = dd.n_own + dd.ghost_from[r], from_e = dd.n_own + dd.ghost_from[r + 1];
      if (from_e > from_b) {
        std::vector<int> stack{cf};
        while (!stack.empty()) {
          const Cell &C = cells[stack.back()];
          stack.pop_back();
          bool holds = false;
          for (uint32_t i = C.trg_begin; i < C.trg_end && !holds; ++i)
            holds = tree.trg_order[i] >= from_b && tree.trg_order[i] < from_e;
          if (!holds) continue;
          asking.push_back({C, C.leaf(), false});
          for (int c2 = 0; c2 < C.n_children; ++c2) stack.push_back(C.first_child + c2);
        }
      }
      send[r].push_back((double) f);
      const std::size_t at = send[r].size();
      let_fragment(tree, cf, asking, shifts, up, nsurf, dd, from_b, from_e, send[r]);
      dd.ghost_bytes += sizeof(double) * 4 * (std::size_t) send[r][at + 1];
    }
    dd.let_bytes += sizeof(double) * send[r].size();
  }
  return send;
}

// The received fragments appended below their frontier cells: cells, densities and points.
void append_let(const std::vector<std::vector<double>> &recv, int nsurf, DistributedData &dd)
{
  TopTree &top = dd.top;
  const int ntop = dd.n_top_global;
  const bool moments = dd.moments;
  const std::size_t w = point_record_size(moments);
  for (const auto &v : recv) {
    std::size_t k = 0;
    while (k < v.size()) {
      const int f = (int) v[k], ncells = (int) v[k + 1];
      const std::size_t npts = (std::size_t) v[k + 2];
      k += 3;
      const int base = (int) top.cells.size(), cf = dd.frontier[f];
      const double *desc = &v[k];
      k += 6 * (std::size_t) ncells;
      for (int j = 0; j < ncells; ++j) {
        const double *e = desc + 6 * j;
        const int par = e[0] < 0 ? cf : base + (int) e[0], oct = (int) e[1];
        Cell ch = child_cell(top.cells[par], par, oct);
        ch.gsrc = (uint32_t) e[2];
        ch.gtrg = (uint32_t) e[3];
        const int idx = (int) top.cells.size();
        if (top.cells[par].n_children == 0) top.cells[par].first_child = idx;
        ++top.cells[par].n_children;
        top.cells[par].child[oct] = idx;
        top.cells.push_back(ch);
        top.open.push_back(e[4] == 2.0);
        dd.let_has_density.push_back(e[5] != 0.0);
        dd.let_density.resize(dd.let_density.size() + nsurf, 0.0);
      }
      for (int j = 0; j < ncells; ++j)
        if (desc[6 * j + 5] != 0.0) {
          std::copy(&v[k], &v[k] + nsurf, &dd.let_density[(std::size_t) (base - ntop + j) * nsurf]);
          k += nsurf;
        }
      for (std::size_t i = 0; i < npts; ++i, k += w) unpack_point(&v[k], moments, dd.xyz, dd.q, dd.mu);
      dd.let_cells += ncells;
    }
  }
}

}    // namespace

void exchange_let(Communicator &comm, const Octree &tree, std::size_t n_own, const std::vector<double> &up, int nsurf,
                  bool periodic, DistributedData &dd)
{
  const Shifts shifts(periodic);
  std::vector<std::vector<int>> got;
  {
    const std::vector<std::vector<int>> req = let_requests(comm.size(), tree, n_own, shifts, dd);
    Timer t(dd.t_comm);
    comm.alltoallv(req, got);
  }
  const std::vector<std::vector<double>> send = let_answers(tree, up, nsurf, shifts, got, dd);
  std::vector<std::vector<double>> recv;
  {
    Timer t(dd.t_comm);
    comm.alltoallv(send, recv);
  }
  append_let(recv, nsurf, dd);
}

}    // namespace kifmm
