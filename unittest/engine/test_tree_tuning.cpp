// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Tuning the tree by timing (kifmm::TreeTuner): the walk along the ladders of octrees and
// single-level grids on given times (it reaches the fastest tree, also across a bump within the
// flat tolerance, keeps the tree in use within the margin, does not time trees modelled far
// slower than it, times the octrees beside the grid of the uniform model, tunes nothing that was
// given), and
// real evaluations during tuning, whose results must all be as accurate as the modelled
// choice's (open: direct sum; periodic: Ewald).
#include "cost_model.h"
#include "periodic.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <omp.h>

using kifmm::KernelSpec;
using namespace kifmm_test;

namespace {

// Runs the tuner to its end with the time of each evaluation given by `time` of the evaluator's
// options (no evaluation); checks that every tree timed is the one the evaluator in use holds.
kifmm::TreeChoice tune_on(kifmm::TreeTuner &tuner, const kifmm::Options &start,
                          const std::function<double(const kifmm::Options &)> &time)
{
  std::unique_ptr<kifmm::Evaluator> ev = kifmm::make_evaluator(KernelSpec{}, start);
  int evaluations = 0;
  while (tuner.tuning() && evaluations < 1000) {
    tuner.select(ev);
    tuner.record(time(ev->options()));
    ++evaluations;
  }
  EXPECT_FALSE(tuner.tuning());
  EXPECT_LE((int) tuner.timed().size(), kifmm::kTuneTrees);
  EXPECT_LE(evaluations, (1 + kifmm::kTuneRepeats) * kifmm::kTuneTrees);
  EXPECT_EQ(evaluations, tuner.evaluations());
  const kifmm::TreeChoice t = tuner.finish(ev);
  EXPECT_EQ(ev->options().leaf_size, t.leaf_size);
  EXPECT_EQ(ev->options().periodic_grid, t.grid);
  return t;
}

// the uniform plan of n points (the distributed evaluation's tree: ladders on uniform points)
kifmm::Options uniform_start(std::size_t n, bool periodic, int order, int grid_request)
{
  kifmm::Options o = periodic ? periodic_options(order, 0) : kifmm::Options{};
  o.order = order;
  return kifmm::plan_tree(o, kifmm::TreeRequest{n, 0, grid_request, true}).options;
}

// the depth of the uniform ladder's tree of this leaf size (leaf_size_for_depth), -1 if none
int uniform_depth(std::size_t n, int leaf)
{
  for (int d = 0; std::ldexp(1.0, 3 * d) <= (double) n; ++d)
    if (kifmm::leaf_size_for_depth(n, d) == leaf) return d;
  return -1;
}

}    // namespace

TEST(TreeTuning, WalksTheOctreeLadderToTheFastestTree)
{
  const std::size_t n = 2000000;
  const kifmm::Options start = uniform_start(n, false, 6, 0);
  const int d0 = kifmm::choose_tree(6, n, false).depth;
  ASSERT_GE(d0, 3);
  for (int target : {d0 - 2, d0 - 1, d0, d0 + 1}) {
    kifmm::TreeTuner tuner(KernelSpec{}, kifmm::TreeRequest{n, 0, 0, true}, start, n, nullptr);
    ASSERT_TRUE(tuner.tuning());
    // the depth of the uniform tree of this leaf size: time 1 at the target depth, more away
    const kifmm::TreeChoice t = tune_on(tuner, start, [&](const kifmm::Options &o) {
      const int d = uniform_depth(n, o.leaf_size);
      EXPECT_GE(d, 0) << "leaf " << o.leaf_size << " is not on the uniform ladder";
      EXPECT_EQ(o.periodic_grid, 0);
      return 1.0 + 0.2 * std::abs(d - target);
    });
    EXPECT_EQ(t.depth, target);
    EXPECT_EQ(t.leaf_size, kifmm::leaf_size_for_depth(n, target));
  }
}

TEST(TreeTuning, CrossesABumpWithinTheFlatTolerance)
{
  // times 1 at the tree in use, slightly more (within kTuneFlat) one depth up, least two depths
  // up: a walk that stopped where both neighbours of the fastest are slower would miss it
  const std::size_t n = 2000000;
  const kifmm::Options start = uniform_start(n, false, 6, 0);
  const int d0 = kifmm::choose_tree(6, n, false).depth;
  ASSERT_GE(d0, 3);
  kifmm::TreeTuner tuner(KernelSpec{}, kifmm::TreeRequest{n, 0, 0, true}, start, n, nullptr);
  ASSERT_TRUE(tuner.tuning());
  const kifmm::TreeChoice t = tune_on(tuner, start, [&](const kifmm::Options &o) {
    const int d = uniform_depth(n, o.leaf_size);
    EXPECT_GE(d, 0) << "leaf " << o.leaf_size << " is not on the uniform ladder";
    if (d == d0 - 1) return 1.0 + 0.8 * kifmm::kTuneFlat;
    if (d == d0 - 2) return 0.85;
    return d == d0 ? 1.0 : 1.3;
  });
  EXPECT_EQ(t.depth, d0 - 2);
}

TEST(TreeTuning, SearchesTheGridsFromTheirModelledBest)
{
  // periodic, grid chosen with the tree: the grid ladder from its tree of least modelled cost,
  // walked to the fastest grid two steps beyond it
  const std::size_t n = 100000;
  const int order = 6;
  const kifmm::Options start = uniform_start(n, true, order, -1);
  kifmm::TreeTuner probe(KernelSpec{}, kifmm::TreeRequest{n, 0, -1, true}, start, n, nullptr);
  int k_least = 0;
  double least = 0;
  for (int k = 3; k <= kifmm::max_grid_cells_long(order, nullptr); ++k) {
    if ((double) k * k * k > n) break;
    const double c = kifmm::modelled_grid_cost(order, n, kifmm::uniform_grid_counts(n, k));
    if (k_least == 0 || c < least) {
      least = c;
      k_least = k;
    }
  }
  const int target = k_least + (start.periodic_grid == k_least ? 2 : 1);
  kifmm::TreeTuner tuner(KernelSpec{}, kifmm::TreeRequest{n, 0, -1, true}, start, n, nullptr);
  const kifmm::TreeChoice t = tune_on(tuner, start, [&](const kifmm::Options &o) {
    return o.periodic_grid > 0 ? 1.0 + 0.1 * std::abs(o.periodic_grid - target) : 2.0;
  });
  EXPECT_EQ(t.grid, target);
}

TEST(TreeTuning, TimesTheOctreesOfTheUniformModelBesideItsGrid)
{
  // several ranks (no points), periodic: the uniform model chooses a grid and models every
  // octree beyond kTuneOtherLadder times it, yet on clustered atoms an octree can be the fastest
  // tree; the octree ladder is timed from its tree of least modelled cost and walked to the
  // fastest octree, or left after that one tree when it is kTuneSlower times the fastest grid
  const std::size_t n = 100000;
  const int order = 4;
  const kifmm::Options start = uniform_start(n, true, order, -1);
  ASSERT_GT(start.periodic_grid, 0);
  const double grid_cost = kifmm::modelled_grid_cost(order, n, kifmm::uniform_grid_counts(n, start.periodic_grid));
  int d_least = -1;
  double least = 0;
  for (int d = 0; std::ldexp(1.0, 3 * d) <= (double) n; ++d) {
    const double c = kifmm::modelled_cost(order, n, true, d);
    if (d_least < 0 || c < least) {
      least = c;
      d_least = d;
    }
  }
  ASSERT_GT(least, kifmm::kTuneOtherLadder * grid_cost);    // the other ladder is not modelled near
  ASSERT_GE(d_least, 1);
  auto depth_of = [&](int leaf) {
    const int d = uniform_depth(n, leaf);
    EXPECT_GE(d, 0) << "leaf " << leaf << " is not on the uniform ladder";
    return d;
  };
  // clustered: the grids 2 and more, the octrees fastest one level above the least modelled one
  const int target = d_least - 1;
  kifmm::TreeTuner clustered(KernelSpec{}, kifmm::TreeRequest{n, 0, -1, true}, start, n, nullptr);
  const kifmm::TreeChoice t = tune_on(clustered, start, [&](const kifmm::Options &o) {
    return o.periodic_grid > 0 ? 2.0 + 0.2 * std::abs(o.periodic_grid - start.periodic_grid)
                               : 1.0 + 0.1 * std::abs(depth_of(o.leaf_size) - target);
  });
  EXPECT_EQ(t.grid, 0);
  EXPECT_EQ(t.leaf_size, kifmm::leaf_size_for_depth(n, target));
  // uniform: the octrees twice the grids' time; one octree timed, once after its warm-up
  kifmm::TreeTuner uniform(KernelSpec{}, kifmm::TreeRequest{n, 0, -1, true}, start, n, nullptr);
  const kifmm::TreeChoice u = tune_on(uniform, start, [&](const kifmm::Options &o) {
    return o.periodic_grid > 0 ? 1.0 + 0.1 * std::abs(o.periodic_grid - start.periodic_grid) : 2.0;
  });
  EXPECT_EQ(u.grid, start.periodic_grid);
  int octrees = 0;
  for (const auto &c : uniform.timed())
    if (c.tree.grid == 0) {
      ++octrees;
      EXPECT_EQ(c.tree.leaf_size, kifmm::leaf_size_for_depth(n, d_least));
      EXPECT_EQ(c.evaluations, 2);
    }
  EXPECT_EQ(octrees, 1);
}

TEST(TreeTuning, KeepsTheTreeInUseWithinTheMargin)
{
  const std::size_t n = 300000;
  const kifmm::Options start = uniform_start(n, false, 6, 0);
  kifmm::TreeTuner tuner(KernelSpec{}, kifmm::TreeRequest{n, 0, 0, true}, start, n, nullptr);
  const kifmm::TreeChoice t = tune_on(tuner, start, [&](const kifmm::Options &o) {
    return o.leaf_size == start.leaf_size ? 1.0 : 1.0 - 0.5 * kifmm::kTuneMargin;
  });
  EXPECT_EQ(t.leaf_size, start.leaf_size);
  // a clearly slower neighbour is timed once (after its warm-up)
  kifmm::TreeTuner slow(KernelSpec{}, kifmm::TreeRequest{n, 0, 0, true}, start, n, nullptr);
  tune_on(slow, start, [&](const kifmm::Options &o) { return o.leaf_size == start.leaf_size ? 1.0 : 2.0; });
  for (const auto &c : slow.timed()) EXPECT_EQ(c.evaluations, c.tree.leaf_size == start.leaf_size ? 3 : 2);
  // fast evaluations are repeated until they add up to kTuneMinSeconds (at most kTuneRepeats)
  for (double t : {1e-3, 0.01}) {
    kifmm::TreeTuner fast(KernelSpec{}, kifmm::TreeRequest{n, 0, 0, true}, start, n, nullptr);
    tune_on(fast, start, [&](const kifmm::Options &) { return t; });
    const int expected = std::min(kifmm::kTuneRepeats, (int) std::ceil(kifmm::kTuneMinSeconds / t - 1e-9));
    for (const auto &c : fast.timed()) EXPECT_EQ(c.evaluations, 1 + expected) << t;    // 1: the warm-up
  }
}

TEST(TreeTuning, DoesNotTimeTreesModelledFarSlower)
{
  // on the points: towards smaller leaves, the ladder's distinct trees (as tree_tuning.cpp
  // builds it) up to the first one modelled beyond kTuneModelled times the tree in use; the
  // times fall towards that one, which the walk does not time, so it stops next to it
  const std::size_t n = 200000;
  const Points p = uniform_cube(n, 11);
  kifmm::Options o;
  o.order = 6;
  const kifmm::TreeRequest request{n, 0, 0, false};
  o = kifmm::plan_tree(o, request).options;
  kifmm::choose_tree_from_points(KernelSpec{}, request, o, n, p.xyz.data());
  const kifmm::TreeChoice in_use = kifmm::model_tree(KernelSpec{}, o, n, p.xyz.data(), o.leaf_size);
  const double limit = kifmm::kTuneModelled * in_use.cost;
  std::vector<kifmm::TreeChoice> below{in_use};
  double leaf = o.leaf_size;
  for (int step = 0; step < 16 && below.size() < 5 && below.back().cost <= limit; ++step) {
    leaf /= std::sqrt(2.0);
    const kifmm::TreeChoice c = kifmm::model_tree(KernelSpec{}, o, n, p.xyz.data(), (int) std::lround(leaf));
    if (c.depth != below.back().depth || c.cost != below.back().cost) below.push_back(c);
  }
  ASSERT_GT(below.back().cost, limit);    // a tree beyond the limit within the ladder's reach
  ASSERT_GE(below.size(), 3u);            // and one between (a walk to time)
  const int far = below.back().leaf_size, stop = below[below.size() - 2].leaf_size;
  kifmm::TreeTuner tuner(KernelSpec{}, request, o, n, p.xyz.data());
  ASSERT_TRUE(tuner.tuning());
  const kifmm::TreeChoice t = tune_on(tuner, o, [&](const kifmm::Options &x) {
    return 1.0 + 0.1 * std::abs(std::log((double) x.leaf_size / far));
  });
  for (const auto &c : tuner.timed()) EXPECT_LE(c.tree.cost, limit) << "leaf " << c.tree.leaf_size;
  EXPECT_EQ(t.leaf_size, stop);
}

TEST(TreeTuning, GivenTreesAreNotTuned)
{
  const std::size_t n = 100000;
  const Points p = neutral(uniform_cube(20000, 3));
  kifmm::Options o = periodic_options(6, 100);
  EXPECT_FALSE(kifmm::TreeTuner(KernelSpec{}, kifmm::TreeRequest{n, 100, -1, false}, o, p.size(), p.xyz.data()).tuning());
  o.periodic_grid = 5;
  EXPECT_FALSE(kifmm::TreeTuner(KernelSpec{}, kifmm::TreeRequest{n, 0, 5, false}, o, p.size(), p.xyz.data()).tuning());
  EXPECT_FALSE(kifmm::TreeTuner(KernelSpec{}, kifmm::TreeRequest{0, 0, -1, false}, o, 0, nullptr).tuning());
  EXPECT_FALSE(kifmm::TreeTuner().tuning());
  // grid no: octrees only
  o.periodic_grid = 0;
  kifmm::TreeTuner octrees(KernelSpec{}, kifmm::TreeRequest{n, 0, 0, false}, o, p.size(), p.xyz.data());
  tune_on(octrees, o, [](const kifmm::Options &x) { return x.periodic_grid > 0 ? 0.1 : 1.0 + 1e-3 * x.leaf_size; });
  for (const auto &c : octrees.timed()) EXPECT_EQ(c.tree.grid, 0);
}

// Real evaluations during tuning on clustered points: every tree timed gives forces as accurate
// as the modelled choice's, and the ladder on the points holds distinct trees only.
TEST(TreeTuning, EveryEvaluationWhileTuningIsAccurate)
{
  for (bool periodic : {false, true}) {
    const std::size_t n = 6000;
    Points p = neutral(two_clusters(n, 5));
    if (periodic)
      for (double &x : p.xyz) x = 0.98 * std::tanh(x);
    kifmm::Options o = periodic ? periodic_options(6, 0) : kifmm::Options{};
    o.order = 6;
    const kifmm::TreeRequest request{n, 0, periodic ? -1 : 0, false};
    o = kifmm::plan_tree(o, request).options;
    kifmm::choose_tree_from_points(KernelSpec{}, request, o, n, p.xyz.data());
    std::vector<double> ep(n), eg(3 * n), pot(n), g(3 * n);
    const double c0[3] = {0, 0, 0};
    if (periodic)
      kifmm::periodic_direct_sum(KernelSpec{}, c0, 1.0, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), ep.data(), eg.data());
    else
      kifmm::direct_sum(KernelSpec{}, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), ep.data(), eg.data());
    std::unique_ptr<kifmm::Evaluator> ev = kifmm::make_evaluator(KernelSpec{}, o);
    ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
    const double first = rel_l2(g, eg);
    kifmm::TreeTuner tuner(KernelSpec{}, request, o, n, p.xyz.data());
    ASSERT_TRUE(tuner.tuning());
    while (tuner.tuning()) {
      tuner.select(ev);
      const double t0 = omp_get_wtime();
      ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
      tuner.record(omp_get_wtime() - t0 - ev->stats().t_precompute);
      const double err = rel_l2(g, eg);
      std::printf("  %s: leaf %d grid %d depth %d: gradient error %.2e (modelled choice %.2e)\n",
                  periodic ? "periodic" : "open", ev->options().leaf_size, ev->options().periodic_grid,
                  ev->stats().depth, err, first);
      EXPECT_LE(err, std::max(4 * first, 1e-6));
      EXPECT_LE(err, 1e-5);
    }
    tuner.finish(ev);
    ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
    EXPECT_LE(rel_l2(g, eg), 1e-5);
    for (std::size_t i = 1; i < tuner.timed().size(); ++i)
      for (std::size_t j = 0; j < i; ++j) {
        const auto &a = tuner.timed()[i].tree, &b = tuner.timed()[j].tree;
        EXPECT_FALSE(a.grid == b.grid && (a.grid > 0 || (a.depth == b.depth && a.cost == b.cost)))
            << "the same tree timed twice: leaf " << a.leaf_size << " and " << b.leaf_size;
      }
  }
}
