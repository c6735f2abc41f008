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

}    // namespace

Options tree_options(const Options &options, const TreeChoice &tree)
{
  Options o = options;
  o.leaf_size = tree.leaf_size;
  o.periodic_grid = tree.grid;
  return o;
}

TreeTuner::TreeTuner(const KernelSpec &kernel, const TreeRequest &request, const Options &options, std::size_t n,
                     const double *xyz, const Options *model) :
    kernel_(kernel), options_(options)
{
  const Options modelled = model ? tree_options(*model, TreeChoice{options.leaf_size, 0, 0.0, options.periodic_grid})
                                 : options;
  const bool slab = options.periodic && options.periodic_dims == 2;
  const double *shape = options.fixed_root ? options.root_shape : nullptr;
  const bool octree = !slab && !(options.periodic && shape && !octree_fits_cell(shape));
  if (n == 0 || request.grid > 0 || (request.leaf_size > 0 && !slab)) return;    // given: not tuned
  if (octree)
    for (const TreeChoice &t : octree_ladder(kernel, modelled, n, xyz)) ladders_[0].push_back(Rung{t});
  if (options.periodic && request.grid < 0)
    for (const TreeChoice &t : model_grids(kernel, modelled, n, xyz, octree)) ladders_[1].push_back(Rung{t});
  // the tree in use starts the walk
  const int first = options.periodic_grid > 0 ? 1 : 0;
  std::size_t at = ladders_[first].size();
  for (std::size_t r = 0; r < ladders_[first].size(); ++r) {
    const TreeChoice &t = ladders_[first][r].tree;
    if (first == 1 ? t.grid == options.periodic_grid : t.leaf_size == options.leaf_size) at = r;
  }
  if (at == ladders_[first].size() || ladders_[0].size() + ladders_[1].size() < 2) return;
  first_ladder_ = first;
  uniform_ = !xyz;
  // on the points only: the uniform ladders (xyz null) miss by more on clustered atoms
  const double in_use_cost = ladders_[first][at].tree.cost;
  if (xyz && in_use_cost > 0) cost_limit_ = kTuneModelled * in_use_cost;
  const std::vector<Rung> &other = ladders_[1 - first];
  if (!other.empty()) {
    const auto least = std::min_element(other.begin(), other.end(),
                                        [](const Rung &a, const Rung &b) { return a.tree.cost < b.tree.cost; });
    // the uniform model cannot tell a clustered set (where an octree beats every grid) from a
    // uniform one: there the other ladder is always timed
    if (uniform_ || least->tree.cost <= kTuneOtherLadder * in_use_cost) other_start_ = least - other.begin();
  }
  done_ = false;
  start(first, at);
  in_use_ = 0;
}

TreeTuner::TreeTuner(const KernelSpec &kernel, const TreeRequest &request, const Options &options,
                     const PointLayout &layout) :
    TreeTuner(kernel, request, options, layout.n, layout.xyz.empty() ? nullptr : layout.xyz.data(),
              layout.xyz.empty() ? nullptr : &layout.model)
{
}

void TreeTuner::start(int ladder, std::size_t rung)
{
  ladder_ = ladder;
  rung_ = rung;
  ladders_[ladder][rung].timed = (int) timed_.size();
  timed_.push_back(Timed{ladders_[ladder][rung].tree, std::numeric_limits<double>::infinity(), 0});
}

// ev becomes the evaluator of timed tree i
void TreeTuner::use(std::unique_ptr<Evaluator> &ev, std::size_t i)
{
  if (i == in_use_) return;
  ev = make_evaluator(kernel_, tree_options(options_, timed_[i].tree));
  in_use_ = i;
}

void TreeTuner::select(std::unique_ptr<Evaluator> &ev)
{
  if (tuning()) use(ev, (std::size_t) ladders_[ladder_][rung_].timed);
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
  ++t.evaluations;    // its least time stays infinite: never the fastest
  use(ev, 0);
  next_tree();
}

// the untimed neighbour of the ladder's fastest tree, or of a tree within kTuneFlat of it (a
// flat stretch of the ladder, where the timings' noise would stop the walk short), if any and
// if modelled within cost_limit_
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
      if (nb >= 0 && nb < (long) rungs.size() && rungs[nb].timed < 0 && !(rungs[nb].tree.cost > cost_limit_)) {
        start(ladder, (std::size_t) nb);
        return true;
      }
  }
  return false;
}

// the fastest time on a ladder is more than kTuneSlower times the fastest of all trees timed
bool TreeTuner::ladder_behind(int ladder) const
{
  double fastest = std::numeric_limits<double>::infinity(), here = fastest;
  for (const Rung &r : ladders_[ladder])
    if (r.timed >= 0) here = std::min(here, timed_[r.timed].least);
  for (const Timed &t : timed_) fastest = std::min(fastest, t.least);
  return here > kTuneSlower * fastest;
}

void TreeTuner::next_tree()
{
  if ((int) timed_.size() < kTuneTrees) {
    // the other ladder of the uniform model, timed without its model's consent, is walked only
    // while it keeps up with the fastest tree
    const bool behind = uniform_ && ladder_ != first_ladder_ && ladder_behind(ladder_);
    if (!behind && walk(ladder_)) return;
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
  if (timed_.empty()) return TreeChoice{options_.leaf_size, 0, 0.0, options_.periodic_grid};    // not tuned
  std::size_t best = (std::size_t) (std::min_element(timed_.begin(), timed_.end(),
                                                     [](const Timed &a, const Timed &b) { return a.least < b.least; }) -
                                    timed_.begin());
  if (timed_[best].least > (1 - kTuneMargin) * timed_[0].least) best = 0;    // the tree in use at the start
  use(ev, best);
  return timed_[best].tree;
}

}    // namespace kifmm
