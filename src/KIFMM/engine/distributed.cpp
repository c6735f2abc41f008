#include "distributed.h"

#include "morton.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace kifmm {

int choose_top_level(uint64_t npoints, int nranks, int nsurf, int max_depth)
{
  const int hi = std::max(0, std::min(5, max_depth));
  int best = std::min(2, hi);
  double best_bytes = std::numeric_limits<double>::max();
  const double per_rank = (double) npoints / std::max(nranks, 1), side = std::cbrt((double) std::max(nranks, 1));
  for (int l = std::min(2, hi); l <= hi; ++l) {
    const double r = side / std::exp2(l), halo = std::pow(1.0 + 2.0 * r, 3) - 1.0;
    const double bytes = (nranks > 1 ? 32.0 * per_rank * halo : 0.0) + 8.0 * nsurf * std::exp2(3 * l);
    if (bytes < best_bytes) {
      best_bytes = bytes;
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

// frontier cells (top cells without children) touching cell x: descend the top tree
template <class F> void touching(const TopTree &top, const Cell &x, F &&visit)
{
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    const Cell &C = top.cells[c];
    if (!cells_adjacent(C, x)) continue;
    if (C.n_children == 0) visit(c);
    else
      for (int k = 0; k < C.n_children; ++k) stack.push_back(C.first_child + k);
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

void distributed_setup(Communicator &comm, int top_level, int leaf_size, int max_depth, int nsurf, bool pow2_root,
                       const RootBox *fixed_root, std::size_t n, const double *xyz, const double *q,
                       DistributedData &out)
{
  out = DistributedData();
  const int nranks = comm.size(), me = comm.rank();
  leaf_size = std::max(leaf_size, 1);
  max_depth = std::min(std::max(max_depth, 0), kMortonBits);
  // root: bounding cube of all points (every point is a target), as bounding_cube()
  double b[6];
  for (int d = 0; d < 3; ++d) b[d] = b[3 + d] = std::numeric_limits<double>::max();
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      b[d] = std::min(b[d], xyz[3 * i + d]);
      b[3 + d] = std::min(b[3 + d], -xyz[3 * i + d]);
    }
  uint64_t cnt[2] = {n, 0};
  for (std::size_t i = 0; i < n; ++i) cnt[1] += q[i] != 0.0;
  {
    Timer t(out.t_comm);
    comm.allreduce_min(b, 6);
    comm.allreduce_sum(cnt, 2);
  }
  out.global_points = cnt[0];
  out.global_sources = cnt[1];
  if (cnt[0] == 0 || cnt[1] == 0) return;
  if (fixed_root) out.root = *fixed_root;
  else {
    const double lo[3] = {b[0], b[1], b[2]}, hi[3] = {-b[3], -b[4], -b[5]};
    out.root = bounding_cube_of(lo, hi);
    if (pow2_root) out.root.half_width = std::exp2(std::ceil(std::log2(out.root.half_width)));
  }

  // counts of the cells of level L and the top tree
  const int L = std::min(top_level > 0 ? top_level : choose_top_level(cnt[0], nranks, nsurf, max_depth), max_depth);
  const std::size_t ncell = std::size_t(1) << (3 * L);
  std::vector<uint64_t> keys;
  morton_keys(out.root, n, xyz, keys);
  const int shift = 3 * (kMortonBits - L);
  std::vector<uint64_t> counts(2 * ncell, 0);
  for (std::size_t i = 0; i < n; ++i) {
    keys[i] >>= shift;
    counts[keys[i]] += q[i] != 0.0;
    ++counts[ncell + keys[i]];
  }
  {
    Timer t(out.t_comm);
    comm.allreduce_sum(counts.data(), counts.size());
  }
  TopTree &top = out.top;
  build_top_tree(top, L, counts.data(), counts.data() + ncell, leaf_size, max_depth);
  const int ntop = (int) top.cells.size();

  // frontier cells and the frontier cell of every level-L cell
  std::vector<int> findex(ntop, -1), of_cell(ncell, -1);
  for (int c = 0; c < ntop; ++c)
    if (top.cells[c].n_children == 0) {
      findex[c] = (int) out.frontier.size();
      out.frontier.push_back(c);
      const Cell &C = top.cells[c];
      const int sh = 3 * (L - C.level);
      std::fill(of_cell.begin() + (std::size_t) (C.prefix << sh), of_cell.begin() + (std::size_t) ((C.prefix + 1) << sh),
                findex[c]);
    }
  const int nf = (int) out.frontier.size();

  // this rank's points by frontier cell (counting sort, input order inside a cell)
  std::vector<int> fstart(nf + 1, 0), fpoints(n);
  for (std::size_t i = 0; i < n; ++i) ++fstart[of_cell[keys[i]] + 1];
  for (int f = 0; f < nf; ++f) fstart[f + 1] += fstart[f];
  {
    std::vector<int> pos(fstart.begin(), fstart.end() - 1);
    for (std::size_t i = 0; i < n; ++i) fpoints[pos[of_cell[keys[i]]]++] = (int) i;
  }
  std::vector<int> mine, all, per_rank;
  for (int f = 0; f < nf; ++f)
    if (fstart[f + 1] > fstart[f]) mine.push_back(f);
  {
    Timer t(out.t_comm);
    comm.allgatherv(mine, all, per_rank);
  }
  // occupants of every frontier cell (ranks in increasing order)
  std::vector<int> ostart(nf + 1, 0), occ(all.size());
  for (int f : all) ++ostart[f + 1];
  for (int f = 0; f < nf; ++f) ostart[f + 1] += ostart[f];
  {
    std::vector<int> pos(ostart.begin(), ostart.end() - 1);
    std::size_t k = 0;
    for (int r = 0; r < nranks; ++r)
      for (int j = 0; j < per_rank[r]; ++j) occ[pos[all[k++]]++] = r;
  }
  out.responsible.assign(nf, 0);
  for (int f = 0; f < nf; ++f) out.responsible[f] = ostart[f + 1] > ostart[f] && occ[ostart[f]] == me;

  // frontier cells whose points this rank needs (doc/design.md: rules i-iii)
  std::vector<char> need(nf, 0), own_top(ntop, 0);
  auto mark = [&](int c) { need[findex[c]] = 1; };
  for (int f : mine) {
    int c = out.frontier[f];
    touching(top, top.cells[c], mark);    // (i)
    for (; c >= 0 && !own_top[c]; c = top.cells[c].parent) own_top[c] = 1;
  }
  for (int c = 1; c < ntop; ++c) {    // (ii) coarser top leaves touching parent(C)
    if (!own_top[c]) continue;
    const Cell &C = top.cells[c];
    touching(top, top.cells[C.parent], [&](int a) {
      if (top.cells[a].level < C.level) mark(a);
    });
  }
  for (int f : mine) {    // (iii) small W-list top cells of own top leaves coarser than L
    const int c = out.frontier[f];
    const Cell &B = top.cells[c];
    if (B.level >= L || top.open[c]) continue;
    std::vector<int> stack;
    // colleagues of B: top cells of B's level touching B, found by descending from the root
    std::vector<int> st{0};
    while (!st.empty()) {
      const int a = st.back();
      st.pop_back();
      const Cell &A = top.cells[a];
      if (!cells_adjacent(A, B)) continue;
      if (A.level == B.level) stack.push_back(a);
      else
        for (int k = 0; k < A.n_children; ++k) st.push_back(A.first_child + k);
    }
    while (!stack.empty()) {
      const int a = stack.back();
      stack.pop_back();
      const Cell &A = top.cells[a];
      for (int k = 0; k < A.n_children; ++k) {
        const int d = A.first_child + k;
        const Cell &D = top.cells[d];
        if (D.gsrc == 0) continue;
        if (!cells_adjacent(D, B)) {
          if ((int) D.gsrc <= nsurf) below(top, d, mark);
        } else
          stack.push_back(d);
      }
    }
  }

  // requests: needed frontier cells from each rank that holds points there
  std::vector<std::vector<int>> req(nranks), got;
  for (int f = 0; f < nf; ++f)
    if (need[f])
      for (int k = ostart[f]; k < ostart[f + 1]; ++k)
        if (occ[k] != me) req[occ[k]].push_back(f);
  {
    Timer t(out.t_comm);
    comm.alltoallv(req, got);
  }
  std::vector<std::vector<double>> send(nranks), recv;
  for (int r = 0; r < nranks; ++r)
    for (int f : got[r])
      for (int k = fstart[f]; k < fstart[f + 1]; ++k) {
        const int i = fpoints[k];
        send[r].insert(send[r].end(), {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], q[i]});
      }
  for (int r = 0; r < nranks; ++r) out.ghost_bytes += sizeof(double) * send[r].size();
  {
    Timer t(out.t_comm);
    comm.alltoallv(send, recv);
  }
  std::size_t nghost = 0;
  for (const auto &v : recv) nghost += v.size() / 4;
  out.n_own = n;
  out.xyz.resize(3 * (n + nghost));
  out.q.resize(n + nghost);
  std::copy(xyz, xyz + 3 * n, out.xyz.begin());
  std::copy(q, q + n, out.q.begin());
  std::size_t k = n;
  for (const auto &v : recv)
    for (std::size_t j = 0; j + 3 < v.size(); j += 4, ++k) {
      out.xyz[3 * k] = v[j];
      out.xyz[3 * k + 1] = v[j + 1];
      out.xyz[3 * k + 2] = v[j + 2];
      out.q[k] = v[j + 3];
    }
}

}    // namespace kifmm
