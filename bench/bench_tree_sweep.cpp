// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Automatic tree against a sweep of leaf sizes. For each point set, size and order: the tree
// kspace_style kifmm takes on one rank without a leaf size (kifmm::plan_tree, then
// kifmm::choose_tree_from_points on the points), and every distinct tree of a sweep of leaf
// sizes (8 .. 8192, factor --factor; leaf sizes that give the same tree as a smaller one are
// timed once; --min-leaf and --max-leaf bound the sweep); with periodic boundaries also every
// single-level grid of k^3 cells within the engine's memory bound (k = 3 .. max_grid_cells_long,
// at every order) with at least 2 and at most --max-leaf points per cell on average and, with
// --max-model-ratio R, a modelled cost at most R times the least modelled cost of the swept
// trees (on clustered points at 1e6 the coarse grids put 1e4-1e5 points into one cell, whose
// near field takes many minutes per evaluation; the model counts those pairs). Single-thread CPU
// time per N-body evaluation (potential + gradient, sources = targets), all candidates
// interleaved in rotating order for --reps rounds, each timed (after one untimed evaluation)
// over at least --min-time seconds. Printed per case: the automatic leaf and depth, the
// fastest swept leaf and depth, their median times, and auto / best (median over the rounds of
// the per-round ratios; 1.00 = the automatic tree is the fastest of the sweep). "leaf (= L)":
// the automatic tree is the swept tree of leaf L (same depth and modelled cost), whose times it
// takes.
// "tuned": the tree kspace_style kifmm keeps after timing the trees near the automatic one
// (kifmm::TreeTuner), and tuned / best as auto / best; "tuning evaluations": how many it timed
// (the trees timed by the tuning, and every timing of the sweep, are printed on stderr).
//   bench_tree_sweep [--sets uniform,plummer,clusters] [--sizes 1e3,1e4,1e5] [--orders 3,6,9,12]
//                    [--periodic] [--reps 3] [--min-time 0.2] [--factor 1.41] [--min-leaf 8]
//                    [--max-leaf 8192] [--max-model-ratio R]
//                    [--data F.data,...]
// Points: unittest/common/kifmm_point_sets.h (uniform in [-1,1]^3, Plummer sphere, two dense
// clusters), or LAMMPS data files with "Atoms # charge" (id type q x y z). Periodic: the points
// scaled into the cell [-1,1]^3, charges made neutral. Run with OMP_NUM_THREADS=1.
#include "bench_points.h"
#include "kifmm.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

double cpu_now()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const std::size_t k = v.size();
  return k % 2 ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
}

// points scaled into [-1,1]^3 (a small margin inside), charges shifted to a zero sum
struct Candidate {
  int leaf = 0, depth = 0;
  std::vector<double> times;
  int grid = 0;    // periodic: single-level grid of grid^3 cells instead of the octree
};

std::string tree_label(int grid, int leaf)
{
  return grid > 0 ? "grid " + std::to_string(grid) + "^3" : std::to_string(leaf);
}

// the bounds of the sweep
struct Range {
  double factor = 1.41, min_leaf = 8, max_leaf = 8192;
  double max_model_ratio = 0;    // > 0: grids modelled dearer than this times the least left out
};

struct Case {
  std::string name;
  bench::Points pts;
};

double time_evaluation(kifmm::Evaluator &ev, const bench::Points &p, std::vector<double> &pot,
                       std::vector<double> &grad, double min_time)
{
  const std::size_t n = p.size();
  // not timed: the first evaluation after another tree's pays for the memory that tree's
  // evaluation released (page faults of its buffers), which a run of one tree does not
  ev.evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), grad.data());
  int k = 0;
  const double t0 = cpu_now();
  double t = 0;
  do {
    ev.evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), grad.data());
    ++k;
    t = cpu_now() - t0;
  } while (t < min_time);
  return t / k;
}

// the swept trees: distinct trees only (same depth and modelled cost = same tree; seen maps
// them to their leaf) and, periodic, every single-level grid within the engine's memory bound
// with at least 2 and at most max_leaf points per cell on average (and, with max_model_ratio,
// modelled at most that many times the least modelled cost of the swept trees)
std::vector<Candidate> swept_trees(const Case &c, const kifmm::Options &opt, const Range &range,
                                   std::map<std::pair<int, double>, int> &seen)
{
  const std::size_t n = c.pts.size();
  std::vector<Candidate> cands;
  double least = std::numeric_limits<double>::infinity();
  for (double leaf = 8; leaf <= range.max_leaf && leaf <= 2.0 * n; leaf *= range.factor) {
    if (leaf < range.min_leaf) continue;
    const int l = (int) std::lround(leaf);
    const kifmm::TreeChoice m = kifmm::model_tree(kifmm::KernelSpec{}, opt, n, c.pts.xyz.data(), l);
    least = std::min(least, m.cost);
    if (seen.emplace(std::make_pair(m.depth, m.cost), l).second) cands.push_back(Candidate{l, m.depth, {}});
  }
  if (!opt.periodic) return cands;
  std::map<int, double> grid_cost;
  if (range.max_model_ratio > 0)
    for (const kifmm::TreeChoice &g : kifmm::model_grids(kifmm::KernelSpec{}, opt, n, c.pts.xyz.data(), false)) {
      grid_cost[g.grid] = g.cost;
      least = std::min(least, g.cost);
    }
  for (int k = 3; k <= kifmm::max_grid_cells_long(opt.order, nullptr) && (k == 3 || 2.0 * k * k * k <= n); ++k) {
    if ((double) n > range.max_leaf * k * k * k) continue;
    const auto g = grid_cost.find(k);
    if (range.max_model_ratio > 0 && g != grid_cost.end() && g->second > range.max_model_ratio * least) {
      std::fprintf(stderr, "%s %zu p%d: grid %d^3 left out (modelled %.4g s, %.3g times the least)\n", c.name.c_str(), n,
                   opt.order, k, g->second, g->second / least);
      continue;
    }
    cands.push_back(Candidate{0, 1, {}, k});
  }
  return cands;
}

// the swept tree that is this tree (the same grid, or the same depth and modelled cost), or -1
int same_swept(const std::vector<Candidate> &cands, const std::map<std::pair<int, double>, int> &seen,
               const Case &c, const kifmm::Options &opt, int leaf, int grid)
{
  int leaf_seen = -1;
  if (grid == 0) {
    const kifmm::TreeChoice m = kifmm::model_tree(kifmm::KernelSpec{}, opt, c.pts.size(), c.pts.xyz.data(), leaf);
    const auto it = seen.find(std::make_pair(m.depth, m.cost));
    if (it == seen.end()) return -1;
    leaf_seen = it->second;
  }
  for (std::size_t i = 0; i < cands.size(); ++i)
    if (cands[i].grid == grid && (grid > 0 || cands[i].leaf == leaf_seen)) return (int) i;
  return -1;
}

// the tuned tree, as kspace_style kifmm tunes it: a walk along the trees near the automatic
// one, each timed on real evaluations (kifmm::TreeTuner); the trees timed on stderr
kifmm::TreeChoice tuned_tree(const Case &c, const kifmm::TreeRequest &request, const kifmm::Options &autom,
                             int &evaluations)
{
  const std::size_t n = c.pts.size();
  std::vector<double> pot(n), grad(3 * n);
  kifmm::TreeTuner tuner(kifmm::KernelSpec{}, request, autom, n, c.pts.xyz.data());
  std::unique_ptr<kifmm::Evaluator> ev = kifmm::make_evaluator(kifmm::KernelSpec{}, autom);
  while (tuner.tuning()) {
    tuner.select(ev);
    const double t0 = cpu_now();
    ev->evaluate(n, c.pts.xyz.data(), c.pts.q.data(), n, c.pts.xyz.data(), pot.data(), grad.data());
    tuner.record(cpu_now() - t0 - ev->stats().t_precompute);
  }
  evaluations = tuner.evaluations();
  for (const auto &t : tuner.timed())
    std::fprintf(stderr, "%s %zu p%d tuning %s: modelled %.4g s, timed %.4g s (%d)\n", c.name.c_str(), n, autom.order,
                 tree_label(t.tree.grid, t.tree.leaf_size).c_str(), t.tree.cost, t.least, t.evaluations);
  return tuner.finish(ev);
}

void sweep(const Case &c, int order, bool periodic, int reps, double min_time, const Range &range)
{
  const std::size_t n = c.pts.size();
  kifmm::Options opt;
  opt.order = order;
  if (periodic) {
    opt.periodic = true;
    opt.fixed_root = true;
    opt.root_half_width = 1.0;
  }
  // the automatic tree, as kspace_style kifmm takes it on one rank
  const kifmm::TreeRequest request{n, 0, periodic ? -1 : 0, false};
  kifmm::Options autom = kifmm::plan_tree(opt, request).options;
  const kifmm::TreeChoice choice = kifmm::choose_tree_from_points(kifmm::KernelSpec{}, request, autom, n, c.pts.xyz.data());
  std::map<std::pair<int, double>, int> seen;
  std::vector<Candidate> cands = swept_trees(c, opt, range, seen);
  // the automatic tree is the last candidate; when a swept tree is the same tree, auto / best
  // uses that candidate's times (the ratio of two timings of one tree only measures the noise)
  const int grid = autom.periodic_grid;
  const int same = grid == 0 ? same_swept(cands, seen, c, opt, autom.leaf_size, 0) : -1;
  int tuning_evaluations = 0;
  const kifmm::TreeChoice tuned = tuned_tree(c, request, autom, tuning_evaluations);
  // the tuned tree's times: the automatic tree's, a swept tree's, or its own
  int tuned_same = tuned.grid == grid && (grid > 0 || tuned.leaf_size == autom.leaf_size)
                       ? (int) cands.size()
                       : same_swept(cands, seen, c, opt, tuned.leaf_size, tuned.grid);
  if (tuned_same < 0) {
    cands.push_back(Candidate{tuned.leaf_size, tuned.depth, {}, tuned.grid});
    tuned_same = (int) cands.size() - 1;
  }
  cands.push_back(Candidate{autom.leaf_size, choice.depth, {}});
  std::vector<std::unique_ptr<kifmm::Evaluator>> evs;
  for (std::size_t i = 0; i < cands.size(); ++i)
    evs.push_back(kifmm::make_evaluator(kifmm::KernelSpec{}, i + 1 == cands.size()
                                                                 ? autom
                                                                 : kifmm::tree_options(opt, kifmm::TreeChoice{cands[i].leaf, 0, 0.0, cands[i].grid})));
  std::vector<double> pot(n), grad(3 * n);
  for (std::size_t i = 0; i < evs.size(); ++i) {    // warm-up: operators, first-touch memory
    evs[i]->evaluate(n, c.pts.xyz.data(), c.pts.q.data(), n, c.pts.xyz.data(), pot.data(), grad.data());
    cands[i].depth = evs[i]->stats().depth;
  }
  const std::size_t m = cands.size();
  for (int r = 0; r < reps; ++r)
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t i = (k + r) % m;
      cands[i].times.push_back(time_evaluation(*evs[i], c.pts, pot, grad, min_time));
      std::fprintf(stderr, "%s %zu p%d round %d: %s%s %.4g s (setup in the last evaluation %.3g s)\n", c.name.c_str(), n,
                   order, r + 1, tree_label(cands[i].grid, cands[i].leaf).c_str(), i + 1 == m ? " (auto)" : "",
                   cands[i].times.back(), evs[i]->stats().t_precompute);
    }
  // fastest swept tree by median; auto / best and tuned / best per round
  std::size_t best = 0;
  for (std::size_t i = 1; i + 1 < m; ++i)
    if (median(cands[i].times) < median(cands[best].times)) best = i;
  const std::vector<double> &auto_times = same >= 0 ? cands[same].times : cands.back().times;
  const std::vector<double> &tuned_times = (std::size_t) tuned_same + 1 == m ? auto_times : cands[tuned_same].times;
  std::vector<double> ratio, tuned_ratio;
  for (int r = 0; r < reps; ++r) {
    ratio.push_back(auto_times[r] / cands[best].times[r]);
    tuned_ratio.push_back(tuned_times[r] / cands[best].times[r]);
  }
  const Candidate &a = cands.back(), &b = cands[best], &t = cands[tuned_same];
  const std::string tuned_label = (std::size_t) tuned_same + 1 == m ? tree_label(grid, a.leaf) : tree_label(t.grid, t.leaf);
  std::printf("| %s | %zu | %d | %s / %s / %s | %d / %d / %d | %.4g / %.4g | %.2f | %.2f | %zu | %d |\n",
              c.name.c_str(), n, order,
              (tree_label(grid, a.leaf) + (same >= 0 ? " (= " + std::to_string(cands[same].leaf) + ")" : "")).c_str(),
              tuned_label.c_str(), tree_label(b.grid, b.leaf).c_str(), a.depth, t.depth, b.depth,
              median(tuned_times), median(b.times), median(ratio), median(tuned_ratio), m - 1, tuning_evaluations);
  std::fflush(stdout);
}

}    // namespace

int main(int argc, char **argv)
{
  std::vector<std::string> sets = {"uniform", "plummer", "clusters"}, files;
  std::vector<double> sizes = {1e3, 1e4, 1e5}, orders = {3, 6, 9, 12};
  bool periodic = false;
  int reps = 3;
  double min_time = 0.2;
  Range range;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--sets") sets = bench::split_list(next());
    else if (a == "--sizes") sizes = bench::number_list(next());
    else if (a == "--orders") orders = bench::number_list(next());
    else if (a == "--data") files = bench::split_list(next());
    else if (a == "--periodic") periodic = true;
    else if (a == "--reps") reps = std::max(1, std::atoi(next().c_str()));
    else if (a == "--min-time") min_time = std::atof(next().c_str());
    else if (a == "--factor") range.factor = std::max(1.05, std::atof(next().c_str()));
    else if (a == "--min-leaf") range.min_leaf = std::atof(next().c_str());
    else if (a == "--max-leaf") range.max_leaf = std::atof(next().c_str());
    else if (a == "--max-model-ratio") range.max_model_ratio = std::atof(next().c_str());
    else {
      std::fprintf(stderr, "bench_tree_sweep: unknown option %s\n", a.c_str());
      return 1;
    }
  }
  std::vector<Case> cases;
  for (double s : sizes)
    for (const auto &name : sets) {
      const std::size_t n = (std::size_t) s;
      if (name == "uniform") cases.push_back({name, kifmm_points::uniform_cube(n, 1)});
      else if (name == "plummer") cases.push_back({name, kifmm_points::plummer(n, 2)});
      else if (name == "clusters") cases.push_back({name, kifmm_points::two_clusters(n, 3)});
      else {
        std::fprintf(stderr, "bench_tree_sweep: unknown point set %s\n", name.c_str());
        return 1;
      }
    }
  for (const auto &f : files) {
    std::string base = f.substr(f.find_last_of('/') + 1);
    cases.push_back({base.substr(0, base.find('.')), bench::read_charge_data(f)});
  }
  std::printf("%s boundaries; CPU s per evaluation, one thread (medians of %d rounds, each over >= %g s)\n\n",
              periodic ? "periodic (cell [-1,1]^3, neutral charges)" : "open", reps, min_time);
  std::printf("| points | N | p | leaf auto / tuned / best | depth auto / tuned / best | s tuned / best | auto/best | "
              "tuned/best | trees swept | tuning evaluations |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (auto &c : cases) {
    if (periodic) c.pts = bench::into_periodic_cell(c.pts);
    for (double p : orders) sweep(c, (int) p, periodic, reps, min_time, range);
  }
  return 0;
}
