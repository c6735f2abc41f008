// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic single-level grid (periodic_grid.h): against the Ewald reference sum and against
// the periodic octree, mutual against one-sided near field, background term, wrapping,
// coincident points, threads, the choice of the cost model, bad input.
#include "periodic.h"

#include "cost_model.h"
#include "fmm_core.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

using kifmm::KernelSpec;
using namespace kifmm_test;

namespace {

kifmm::Options grid_opts(int order, int k, double h = 1.0, const double c[3] = nullptr)
{
  return periodic_options(order, 0, h, c, k);
}

struct Result {
  std::vector<double> pot, grad;
  kifmm::Stats stats;
};

Result evaluate(const kifmm::Options &o, const Points &p, const Points *targets = nullptr,
                const KernelSpec &k = KernelSpec{})
{
  const Points &t = targets ? *targets : p;
  Result r{std::vector<double>(t.size()), std::vector<double>(3 * t.size()), {}};
  auto ev = kifmm::make_evaluator(k, o);
  ev->evaluate(p.size(), p.xyz.data(), p.q.data(), t.size(), targets ? t.xyz.data() : p.xyz.data(), r.pot.data(),
               r.grad.data());
  r.stats = ev->stats();
  return r;
}

Reference ewald(const kifmm::Options &o, const Points &p)
{
  const std::size_t n = p.size();
  Reference r{std::vector<double>(n), std::vector<double>(3 * n)};
  kifmm::periodic_direct_sum(KernelSpec{}, o.root_center, o.root_half_width, n, p.xyz.data(), p.q.data(), n,
                             p.xyz.data(), r.pot.data(), r.grad.data());
  return r;
}

double max_abs_diff(const std::vector<double> &a, const std::vector<double> &b)
{
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

}    // namespace

TEST(PeriodicGrid, NeutralMatchesEwaldAndConvergesWithOrder)
{
  Points p = neutral(uniform_cube(3000, 31));
  const Reference ref = ewald(grid_opts(4, 3), p);
  for (int k : {3, 5, 8}) {
    double prev = 1;
    for (int order : {4, 6, 8, 10, 12}) {
      const Result r = evaluate(grid_opts(order, k), p);
      const double ep = rel_l2(r.pot, ref.pot), eg = rel_l2(r.grad, ref.grad);
      std::printf("  grid %d^3 p=%2d: pot %.2e grad %.2e\n", k, order, ep, eg);
      EXPECT_LT(eg, order >= 12 ? 1e-9 : prev) << k << " " << order;
      EXPECT_LT(ep, 10 * eg + 1e-12);
      EXPECT_EQ(r.stats.n_leaves, (std::size_t) k * k * k);
      prev = eg;
    }
  }
}

// A net charge (uniform background, as the octree path and Ewald), in a cell of half-width
// 1.5 centered away from the origin, points given outside the cell (wrapped).
TEST(PeriodicGrid, NonNeutralShiftedScaledCellWithOutsidePointsMatchesEwald)
{
  Points p = uniform_cube(2000, 32);
  for (double &q : p.q) q += 0.3;
  const double c[3] = {0.5, -2.0, 10.0};
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] = c[d] + 1.5 * p.xyz[3 * i + d] + (i % 3 == 0 ? 3.0 * (d - 1) : 0.0);
  const Reference ref = ewald(grid_opts(4, 3, 1.5, c), p);
  for (int order : {6, 12}) {
    const Result r = evaluate(grid_opts(order, 4, 1.5, c), p);
    const double ep = rel_l2(r.pot, ref.pot), eg = rel_l2(r.grad, ref.grad);
    std::printf("  grid non-neutral p=%2d: pot %.2e grad %.2e\n", order, ep, eg);
    EXPECT_LT(ep, order == 6 ? 1e-4 : 1e-9);
    EXPECT_LT(eg, order == 6 ? 1e-4 : 1e-9);
  }
}

// Hard cases: cancelling dipoles, and a dense cluster at the cell's corner whose near images
// are across the faces (most cells empty, a few holding everything)
TEST(PeriodicGrid, DipolesAndCornerClusterMatchEwald)
{
  Points d = dipoles(1500, 33);
  Result r = evaluate(grid_opts(12, 5), d);
  Reference ref = ewald(grid_opts(12, 5), d);
  std::printf("  grid dipoles p=12: pot %.2e grad %.2e\n", rel_l2(r.pot, ref.pot), rel_l2(r.grad, ref.grad));
  EXPECT_LT(rel_l2(r.grad, ref.grad), 1e-8);
  Points c = gaussian_cluster(3000, 0.97, 0.03, 5);
  r = evaluate(grid_opts(12, 6), c);
  ref = ewald(grid_opts(12, 6), c);
  std::printf("  grid corner cluster p=12: pot %.2e grad %.2e\n", rel_l2(r.pot, ref.pot), rel_l2(r.grad, ref.grad));
  EXPECT_LT(rel_l2(r.grad, ref.grad), 1e-8);
}

// The grid and the octree are two discretizations of the same sum: equal at high order
TEST(PeriodicGrid, EqualsThePeriodicOctreeAtHighOrder)
{
  Points p = neutral(uniform_cube(4000, 34));
  const kifmm::Options oct = periodic_options(13, 64);
  const Result a = evaluate(grid_opts(13, 7), p), b = evaluate(oct, p);
  EXPECT_GT(b.stats.depth, 0);
  EXPECT_LT(rel_l2(a.grad, b.grad), 1e-9);
  EXPECT_LT(rel_l2(a.pot, b.pot), 1e-9);
}

// Targets that are not the sources (zero-strength atoms leave the sources; separate target
// arrays): the one-sided near field equals the mutual one
TEST(PeriodicGrid, OneSidedNearFieldEqualsMutual)
{
  Points p = neutral(uniform_cube(2500, 35));
  const Result mutual = evaluate(grid_opts(8, 5), p);
  EXPECT_GT(mutual.stats.mutual_pairs, 0u);
  Points copy = p;    // same coordinates, other arrays: sources != targets
  const Result one = evaluate(grid_opts(8, 5), p, &copy);
  EXPECT_EQ(one.stats.mutual_pairs, 0u);
  EXPECT_LT(max_abs_diff(one.grad, mutual.grad), 1e-11 * (1 + max_abs_diff(mutual.grad, std::vector<double>(mutual.grad.size()))));
  EXPECT_LT(rel_l2(one.pot, mutual.pot), 1e-13);
  // zero-strength points: targets only
  Points z = p;
  for (std::size_t i = 0; i < z.size(); i += 4) z.q[i] = 0.0;
  const Result rz = evaluate(grid_opts(10, 5), z);
  const Reference ref = ewald(grid_opts(10, 5), z);
  EXPECT_EQ(rz.stats.n_sources, z.size() - (z.size() + 3) / 4);
  EXPECT_LT(rel_l2(rz.grad, ref.grad), 1e-7);
}

// Yukawa: the screened lattice sum (kappa H = 1.5 and 6: screened Ewald split; 15: direct
// image sum), in a cell of half-width 1.5
TEST(PeriodicGrid, YukawaMatchesLatticeSum)
{
  Points p = uniform_cube(2000, 41);
  for (double &x : p.xyz) x *= 1.5;
  for (double kappa : {1.0, 4.0, 10.0}) {
    const KernelSpec k{kifmm::KernelType::Yukawa, kappa};
    const kifmm::Options o = grid_opts(10, 5, 1.5);
    const Result r = evaluate(o, p, nullptr, k);
    std::vector<double> rp(p.size()), rg(3 * p.size());
    kifmm::periodic_direct_sum(k, o.root_center, o.root_half_width, p.size(), p.xyz.data(), p.q.data(), p.size(),
                               p.xyz.data(), rp.data(), rg.data());
    std::printf("  grid yukawa kappa H %4.1f p=10: pot %.2e grad %.2e\n", kappa * 1.5, rel_l2(r.pot, rp),
                rel_l2(r.grad, rg));
    EXPECT_LT(rel_l2(r.pot, rp), 1e-7) << kappa;
    EXPECT_LT(rel_l2(r.grad, rg), 1e-7) << kappa;
  }
}

// Coincident points: finite results, the pairs at r = 0 counted and left out like the
// reference (which skips only the bare n = 0 term)
TEST(PeriodicGrid, CoincidentPointsAreFiniteAndCounted)
{
  Points p = neutral(uniform_cube(1000, 36));
  for (int i = 0; i < 10; ++i) {    // 10 duplicates of the first 10 points
    p.xyz.insert(p.xyz.end(), p.xyz.begin() + 3 * i, p.xyz.begin() + 3 * i + 3);
    p.q.push_back(0.5);
  }
  const Result r = evaluate(grid_opts(10, 4), p);
  for (double v : r.grad) ASSERT_TRUE(std::isfinite(v));
  for (double v : r.pot) ASSERT_TRUE(std::isfinite(v));
  EXPECT_EQ(r.stats.coincident_pairs, 20u);
  const Reference ref = ewald(grid_opts(10, 4), p);
  EXPECT_LT(rel_l2(r.grad, ref.grad), 1e-7);
}

// The result does not depend on the number of threads (fixed accumulation order per target)
TEST(PeriodicGrid, ThreadIndependent)
{
  Points p = neutral(uniform_cube(3000, 37));
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const Result a = evaluate(grid_opts(6, 6), p);
  omp_set_num_threads(3);
  const Result b = evaluate(grid_opts(6, 6), p);
  omp_set_num_threads(saved);
  EXPECT_EQ(max_abs_diff(a.grad, b.grad), 0.0);
  EXPECT_EQ(max_abs_diff(a.pot, b.pot), 0.0);
}

// No potential asked: no potential work, same gradient
TEST(PeriodicGrid, GradientOnlyEqualsFullEvaluation)
{
  Points p = neutral(uniform_cube(2000, 38));
  const Result full = evaluate(grid_opts(6, 5), p);
  std::vector<double> g(3 * p.size());
  kifmm::make_evaluator(KernelSpec{}, grid_opts(6, 5))
      ->evaluate(p.size(), p.xyz.data(), p.q.data(), p.size(), p.xyz.data(), nullptr, g.data());
  EXPECT_LT(max_abs_diff(g, full.grad), 1e-12 * (1 + max_abs_diff(full.grad, std::vector<double>(g.size()))));
}

// The cost model picks a grid for uniform points at 1e4 (where it is measured faster than the
// octree: bench_periodic), keeps the octree's leaf size for the distributed evaluation, never
// offers a grid to Yukawa, and for a dense cluster in a large cell (a uniform grid would put
// almost all points into a few cells) keeps the octree.
TEST(PeriodicGrid, CostModelChoice)
{
  Points p = neutral(uniform_cube(10000, 39));
  kifmm::Options o = grid_opts(6, 0);
  const kifmm::TreeChoice c = kifmm::choose_tree(KernelSpec{}, o, p.size(), p.xyz.data());
  EXPECT_GE(c.grid, 4);
  EXPECT_LE(c.grid, kifmm::max_grid_cells(6));
  // Yukawa too (same counts and constants)
  EXPECT_EQ(kifmm::choose_tree(KernelSpec{kifmm::KernelType::Yukawa, 2.0}, o, p.size(), p.xyz.data()).grid, c.grid);
  // the octree's choice is kept beside it (distributed evaluation): a depth >= 2 tree
  EXPECT_GE(c.depth, 2);
  EXPECT_LT(c.leaf_size, (int) p.size());
  const Points c2 = gaussian_cluster(10000, 0.3, 0.01, 6);
  const kifmm::TreeChoice cc = kifmm::choose_tree(KernelSpec{}, o, c2.size(), c2.xyz.data());
  EXPECT_EQ(cc.grid, 0);
  EXPECT_GE(cc.depth, 4);
  // uniform counts: 27 neighbour cells, pairs = 27 k^3 m^2 / 2
  const kifmm::TreeCounts u = kifmm::uniform_grid_counts(8000, 5);
  EXPECT_DOUBLE_EQ(u.near_pairs, 27.0 * 125 * 64.0 * 64.0 / 2);
  EXPECT_DOUBLE_EQ(u.cells, 125.0);
  EXPECT_EQ(kifmm::max_grid_cells(20), 0);
}

// On several ranks every rank does the grid's whole convolution over the cells and the forward
// surface transforms of all occupied cells (evaluate_distributed), while the rest of the work
// goes with the points: the model counts the cell term and the transforms 1 / share times
// (Options::model_share: the largest share of the points on one rank; P ranks in balance: P
// times), so more ranks choose grids of no more cells, and fewer where the convolution weighs;
// all points on one rank is the one-rank model.
TEST(PeriodicGrid, CostModelCountsTheConvolutionOnEveryRank)
{
  const Points p = neutral(uniform_cube(10000, 39));
  int fewer = 0;
  for (int order : {5, 7, 9, 11, 13}) {
    kifmm::Options o = grid_opts(order, 0);
    const std::vector<kifmm::TreeChoice> one = kifmm::model_grids(KernelSpec{}, o, p.size(), p.xyz.data(), true);
    ASSERT_FALSE(one.empty());
    const kifmm::GridCostConstants g = kifmm::grid_cost_constants(order);
    EXPECT_GT(g.forward, 0.0);
    EXPECT_LT(g.forward, g.occupied);    // a part of the occupied cell's work
    int cells = 1 << 30;
    for (int ranks : {1, 2, 4, 8}) {
      o.model_share = 1.0 / ranks;
      const std::vector<kifmm::TreeChoice> grids = kifmm::model_grids(KernelSpec{}, o, p.size(), p.xyz.data(), true);
      ASSERT_EQ(grids.size(), one.size());
      for (std::size_t i = 0; i < grids.size(); ++i) {
        const kifmm::TreeCounts t = kifmm::grid_counts(p.size(), p.xyz.data(), o.root_center, o.root_half_width, grids[i].grid);
        EXPECT_GT(t.occupied_cells, 0.0);
        const double repeated = g.cell * kifmm::grid_convolution_cells(t.cells) + g.forward * t.occupied_cells;
        EXPECT_NEAR(grids[i].cost, one[i].cost + (ranks - 1) * repeated, 1e-12 * one[i].cost) << order << " " << ranks;
      }
      const kifmm::TreeChoice c = kifmm::choose_tree(KernelSpec{}, o, p.size(), p.xyz.data());
      if (c.grid == 0) break;    // the octree: no grid on more ranks either
      EXPECT_LE(c.grid, cells) << "order " << order << ", " << ranks << " ranks";
      if (c.grid < cells && ranks > 1) ++fewer;
      cells = c.grid;
    }
  }
  EXPECT_GT(fewer, 0);
}

TEST(PeriodicGrid, BadOptionsThrow)
{
  Points p = neutral(uniform_cube(100, 40));
  std::vector<double> g(3 * p.size());
  EXPECT_THROW(kifmm::make_evaluator(KernelSpec{}, grid_opts(6, 2))
                   ->evaluate(p.size(), p.xyz.data(), p.q.data(), p.size(), p.xyz.data(), nullptr, g.data()),
               std::invalid_argument);
}
