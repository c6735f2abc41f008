// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Tuning the tree by timing (kifmm.h: TreeTuner): a walk along the ladders of octrees and
// single-level grids near the modelled choice, timed on real evaluations.
#include "cost_model.h"
#include "kifmm.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kifmm {

namespace {
bool same_octree(const TreeChoice &a, const TreeChoice &b)
{
  return a.depth == b.depth && a.cost == b.cost;
}

// octrees by leaf size, distinct trees only: on one process's points, up to kLadderSide trees on
// either side of the leaf size in use, in steps of sqrt(2) (the same tree is skipped: larger leaves
// often give the same tree up to the occupancy of the next level's cells); else (xyz null) the
// full trees over n uniform points, depths log8 n .. 0
constexpr int kLadderSide = 4;
std::vector<TreeChoice> octree_ladder(const KernelSpec &kernel, const Options &o, std::size_t n, const double *xyz)
{
  std::vector<TreeChoice> out;
  if (!xyz) {
    for (int d = 0; d == 0 || std::ldexp(1.0, 3 * d) <= (double) n; ++d)
      out.insert(out.begin(), TreeChoice{leaf_size_for_depth(n, d), d,
                                         modelled_cost(o.order, n, o.periodic, d, o.near_pair_weight)});
    return out;
  }
  const TreeChoice in_use = model_tree(kernel, o, n, xyz, o.leaf_size);
  std::vector<TreeChoice> below, above;
  for (int side : {-1, 1}) {
    std::vector<TreeChoice> &v = side < 0 ? below : above;
    double leaf = o.leaf_size;
    for (int step = 0; step < 4 * kLadderSide && (int) v.size() < kLadderSide; ++step) {
      leaf *= std::pow(2.0, 0.5 * side);
      if (leaf < 1 || leaf > 2.0 * n + 2) break;
      const TreeChoice c = model_tree(kernel, o, n, xyz, (int) std::lround(leaf));
      if (!same_octree(c, v.empty() ? in_use : v.back())) v.push_back(c);
    }
  }
  out.assign(below.rbegin(), below.rend());
  out.push_back(in_use);
  out.insert(out.end(), above.begin(), above.end());
  return out;
}

// the single-level grids choose_tree offers, by cells per side (in cells the octree fits: at
// the orders whose grid cost is fitted, at most one cell per point)
std::vector<TreeChoice> grid_ladder(const KernelSpec &kernel, const Options &o, std::size_t n, const double *xyz,
                                    bool octree)
{
  std::vector<TreeChoice> out;
  const bool open_z = o.periodic_dims == 2;
  const double *shape = o.fixed_root ? o.root_shape : nullptr;
  const double *sh = shape && !(shape[0] == 1.0 && shape[1] == 1.0 && shape[2] == 1.0) ? shape : nullptr;
  if (octree && max_grid_cells(o.order) == 0) return out;
  for (int k = 3; k <= max_grid_cells_long(o.order, sh); ++k) {
    if (!grid_fits_cell(o.order, k, sh, open_z)) continue;
    const TreeCounts u = uniform_grid_counts(n, k, sh, open_z);
    if (octree && u.cells > (double) n) break;
    TreeChoice g = xyz ? model_grid(kernel, o, n, xyz, k)
                       : TreeChoice{0, 0, modelled_grid_cost(o.order, n, u, o.near_pair_weight), k};
    g.leaf_size = o.leaf_size;    // kept with the grid (the distributed evaluation's octree)
    out.push_back(g);
  }
  return out;
}
}    // namespace

Options tree_options(const Options &options, const TreeChoice &tree)
{
  Options o = options;
  o.leaf_size = tree.leaf_size;
  o.periodic_grid = tree.grid;
  return o;
}

TreeTuner::TreeTuner(const KernelSpec &kernel, const TreeRequest &request, const Options &options, std::size_t n,
                     const double *xyz) :
    kernel_(kernel), options_(options)
{
  const bool slab = options.periodic && options.periodic_dims == 2;
  const double *shape = options.fixed_root ? options.root_shape : nullptr;
  const bool octree = !slab && !(options.periodic && shape && !octree_fits_cell(shape));
  if (n == 0 || request.grid > 0 || (request.leaf_size > 0 && !slab)) return;    // given: not tuned
  if (octree) ladders_[0] = [&] {
    std::vector<Rung> r;
    for (const TreeChoice &t : octree_ladder(kernel, options, n, xyz)) r.push_back(Rung{t});
    return r;
  }();
  if (options.periodic && request.grid < 0)
    for (const TreeChoice &t : grid_ladder(kernel, options, n, xyz, octree)) ladders_[1].push_back(Rung{t});
  // the tree in use starts the walk
  const int first = options.periodic_grid > 0 ? 1 : 0;
  std::size_t at = ladders_[first].size();
  for (std::size_t r = 0; r < ladders_[first].size(); ++r) {
    const TreeChoice &t = ladders_[first][r].tree;
    if (first == 1 ? t.grid == options.periodic_grid : t.leaf_size == options.leaf_size) at = r;
  }
  if (at == ladders_[first].size() || ladders_[0].size() + ladders_[1].size() < 2) return;
  first_ladder_ = first;
  const std::vector<Rung> &other = ladders_[1 - first];
  if (!other.empty()) {
    const auto least = std::min_element(other.begin(), other.end(),
                                        [](const Rung &a, const Rung &b) { return a.tree.cost < b.tree.cost; });
    if (least->tree.cost <= kTuneOtherLadder * ladders_[first][at].tree.cost) other_start_ = least - other.begin();
  }
  done_ = false;
  start(first, at);
  in_use_ = 0;
}

void TreeTuner::start(int ladder, std::size_t rung)
{
  ladder_ = ladder;
  rung_ = rung;
  ladders_[ladder][rung].timed = (int) timed_.size();
  timed_.push_back(Timed{ladders_[ladder][rung].tree, std::numeric_limits<double>::infinity(), 0});
}

void TreeTuner::select(std::unique_ptr<Evaluator> &ev)
{
  if (!tuning()) return;
  const std::size_t next = (std::size_t) ladders_[ladder_][rung_].timed;
  if (next == in_use_) return;
  ev = make_evaluator(kernel_, tree_options(options_, timed_[next].tree));
  in_use_ = next;
}

void TreeTuner::record(double seconds)
{
  if (!tuning()) return;
  ++evaluations_;
  Timed &t = timed_[in_use_];
  // the first evaluation of a tree warms it up (first-touch memory; its setup time is not
  // separated exactly): not timed
  if (++t.evaluations == 1) return;
  t.least = std::min(t.least, seconds);
  t.total += seconds;
  const int samples = t.evaluations - 1;
  double fastest_other = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < timed_.size(); ++i)
    if (i != in_use_) fastest_other = std::min(fastest_other, timed_[i].least);
  const bool enough = samples >= 2 && (t.total >= kTuneMinSeconds || samples >= kTuneRepeats);
  if (!enough && !(t.least > kTuneSlower * fastest_other)) return;    // timed again
  next_tree();
}

void TreeTuner::reject(std::unique_ptr<Evaluator> &ev)
{
  if (!tuning()) return;
  ++evaluations_;
  Timed &t = timed_[in_use_];
  t.rejected = true;
  t.least = std::numeric_limits<double>::infinity();
  ++t.evaluations;
  ev = make_evaluator(kernel_, tree_options(options_, timed_[0].tree));
  in_use_ = 0;
  next_tree();
}

// the untimed neighbour of the ladder's fastest tree, or of a tree within kTuneFlat of it (a
// flat stretch of the ladder, where the timings' noise would stop the walk short), if any
bool TreeTuner::walk(int ladder)
{
  std::vector<Rung> &rungs = ladders_[ladder];
  long best = -1;
  for (std::size_t r = 0; r < rungs.size(); ++r)
    if (rungs[r].timed >= 0 && (best < 0 || timed_[rungs[r].timed].least < timed_[rungs[best].timed].least))
      best = (long) r;
  if (best < 0 || timed_[rungs[best].timed].rejected) return false;
  const double flat = (1 + kTuneFlat) * timed_[rungs[best].timed].least;
  for (long r = 0; r < (long) rungs.size(); ++r) {
    if (r != best && (rungs[r].timed < 0 || !(timed_[rungs[r].timed].least <= flat))) continue;
    for (long nb : {r - 1, r + 1})
      if (nb >= 0 && nb < (long) rungs.size() && rungs[nb].timed < 0) {
        start(ladder, (std::size_t) nb);
        return true;
      }
  }
  return false;
}

void TreeTuner::next_tree()
{
  if ((int) timed_.size() < kTuneTrees) {
    if (walk(ladder_)) return;
    if (ladder_ == first_ladder_ && other_start_ >= 0) {
      start(1 - first_ladder_, (std::size_t) other_start_);
      other_start_ = -1;
      return;
    }
  }
  done_ = true;
}

TreeChoice TreeTuner::finish(std::unique_ptr<Evaluator> &ev)
{
  done_ = true;
  if (timed_.empty()) return ev ? TreeChoice{ev->options().leaf_size, 0, 0.0, ev->options().periodic_grid}
                                : TreeChoice{options_.leaf_size, 0, 0.0, options_.periodic_grid};
  std::size_t best = (std::size_t) (std::min_element(timed_.begin(), timed_.end(),
                                                     [](const Timed &a, const Timed &b) { return a.least < b.least; }) -
                                    timed_.begin());
  if (timed_[best].least > (1 - kTuneMargin) * timed_[0].least) best = 0;    // the tree in use at the start
  if (best != in_use_) {
    ev = make_evaluator(kernel_, tree_options(options_, timed_[best].tree));
    in_use_ = best;
  }
  return timed_[best].tree;
}

}    // namespace kifmm
