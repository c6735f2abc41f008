// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Slabs (periodic in x and y, open in z; Options::periodic_dims = 2): the doubly periodic Ewald
// reference (slab_ewald.h) against the vacuum limit of the 3-d Ewald sum with the slab dipole
// correction, and the single-level grid against that reference.
#include "periodic.h"

#include "cost_model.h"
#include "fmm_core.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

using kifmm::KernelSpec;
using kifmm::KernelType;
using namespace kifmm_test;

namespace {

// Points uniform in [c - h shape, c + h shape) (charges in [-1, 1], made neutral unless shift).
Points slab_points(std::size_t n, unsigned seed, const double c[3], double h, const double shape[3], double shift = 0)
{
  Points p = neutral(uniform_cube(n, seed));
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] = c[d] + h * shape[d] * p.xyz[3 * i + d];
    p.q[i] += shift;
  }
  return p;
}

kifmm::Options slab_options(int order, int grid, const double c[3], double h, const double shape[3])
{
  kifmm::Options o = periodic_options(order, 40, h, c, grid);
  o.periodic_dims = 2;
  for (int d = 0; d < 3; ++d) o.root_shape[d] = shape[d];
  return o;
}

struct SlabErrors {
  double pot, grad;
};

// the reference of these points in the slab of these options
Reference slab_reference(const kifmm::Options &o, const Points &p)
{
  const std::size_t n = p.size();
  Reference r{std::vector<double>(n), std::vector<double>(3 * n)};
  kifmm::slab_direct_sum(o.root_center, o.root_half_width, o.root_shape, n, p.xyz.data(), p.q.data(), n, p.xyz.data(),
                         r.pot.data(), r.grad.data());
  return r;
}

SlabErrors slab_errors(const kifmm::Options &o, const Points &p, const Reference &ref)
{
  const std::size_t n = p.size();
  std::vector<double> pot(n), g(3 * n);
  kifmm::make_evaluator(KernelSpec{}, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
  return {rel_l2(pot, ref.pot), rel_l2(g, ref.grad)};
}

}    // namespace

// ---------------------------------------------------------------- the reference

TEST(PeriodicSlab, ReferenceIsTheVacuumLimitOfEwaldWithTheSlabCorrection)
{
  // neutral charges in the slab |z| < 0.4 of the x-y cell [-1, 1)^2; the 3-d tin-foil Ewald sum
  // of the cell stretched to a z period of 2 S (vacuum between the images) plus the dipole
  // correction of Yeh and Berkowitz (grad_z += 4 pi M_z / V) converges to the doubly periodic
  // sum as S grows
  const double c[3] = {0, 0, 0}, shape[3] = {1.0, 1.0, 0.4};
  Points p = slab_points(300, 61, c, 1.0, shape);
  const std::size_t n = p.size();
  std::vector<double> rp(n), rg(3 * n);
  kifmm::slab_direct_sum(c, 1.0, shape, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), rp.data(), rg.data());
  double Mz = 0;
  for (std::size_t i = 0; i < n; ++i) Mz += p.q[i] * p.xyz[3 * i + 2];
  double prev = 1;
  for (double S : {2.0, 4.0, 8.0}) {
    // the 3-d cell of half-widths (S, S, S) * (1/S, 1/S, 1) = (1, 1, S)
    const double sh[3] = {1.0 / S, 1.0 / S, 1.0};
    std::vector<double> g(3 * n), v(n);
    kifmm::periodic_direct_sum(KernelSpec{}, c, S, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), v.data(), g.data(), sh);
    const double V = 2.0 * 2.0 * 2.0 * S;
    for (std::size_t i = 0; i < n; ++i) g[3 * i + 2] += 4 * M_PI * Mz / V;
    const double e = rel_l2(g, rg);
    std::printf("  slab vs 3-d Ewald + dipole correction, z period %4.1f: gradient %.2e\n", 2 * S, e);
    EXPECT_LT(e, prev);
    prev = e;
  }
  EXPECT_LT(prev, 1e-4);
}

TEST(PeriodicSlab, TheThreeDimensionalRouteEqualsTheReference)
{
  // slab_gradient_via_3d (what the error check uses for large systems) against the exact sum,
  // neutral and with a net charge (the terms of Ballenegger, Arnold and Cerda)
  const double c[3] = {0.3, -0.2, 1.0}, shape[3] = {1.0, 0.7, 0.5};
  for (double shift : {0.0, 0.4}) {
    Points p = slab_points(300, 66, c, 1.2, shape, shift);
    const std::size_t n = p.size();
    std::vector<double> a(3 * n), b(3 * n);
    kifmm::slab_direct_sum(c, 1.2, shape, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), nullptr, a.data());
    kifmm::slab_gradient_via_3d(c, 1.2, shape, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), b.data());
    std::printf("  3-d route, net charge %.1f: gradient %.2e\n", shift * n, rel_l2(b, a));
    EXPECT_LT(rel_l2(b, a), 1e-10) << shift;
  }
}

TEST(PeriodicSlab, ReferenceIsPeriodicInXAndYAndItsGradientIsTheDerivative)
{
  const double c[3] = {0, 0, 0}, shape[3] = {1.0, 0.7, 0.5};
  Points p = slab_points(40, 62, c, 1.0, shape, 0.1);    // net charge too
  const double t[3] = {0.3, -0.2, 0.45};
  double v0, g0[3];
  kifmm::slab_direct_sum(c, 1.0, shape, p.size(), p.xyz.data(), p.q.data(), 1, t, &v0, g0);
  for (int d = 0; d < 2; ++d) {
    double ts[3] = {t[0], t[1], t[2]}, v, g[3];
    ts[d] += 2.0 * shape[d];
    kifmm::slab_direct_sum(c, 1.0, shape, p.size(), p.xyz.data(), p.q.data(), 1, ts, &v, g);
    EXPECT_NEAR(v, v0, 1e-11 * std::fabs(v0) + 1e-12);
  }
  for (int d = 0; d < 3; ++d) {
    const double e = 1e-5;
    double tp[3] = {t[0], t[1], t[2]}, tm[3] = {t[0], t[1], t[2]}, vp, vm, g[3];
    tp[d] += e;
    tm[d] -= e;
    kifmm::slab_direct_sum(c, 1.0, shape, p.size(), p.xyz.data(), p.q.data(), 1, tp, &vp, g);
    kifmm::slab_direct_sum(c, 1.0, shape, p.size(), p.xyz.data(), p.q.data(), 1, tm, &vm, g);
    EXPECT_NEAR((vp - vm) / (2 * e), g0[d], 1e-6 * (std::fabs(g0[d]) + 1)) << d;
  }
}

// ---------------------------------------------------------------- the grid against the reference

TEST(PeriodicSlab, GridMatchesTheDoublyPeriodicSum)
{
  struct Case {
    double shape[3];
    int k;
    double shift;
  };
  // a flat slab, a tall one, a rectangular floor; neutral and with a net charge; columns of 2 x 2
  // and 2 x 1 cells across (one neighbour met at two shifts, a cell's own images); stretched
  // cells (12 x 12 x 2 of 1 x 1 x 0.75, 5 layers in the near field along the open z)
  const Case cases[] = {{{1.0, 1.0, 0.5}, 6, 0.0},    {{0.5, 0.5, 1.0}, 6, 0.0},
                        {{1.0, 0.6, 0.4}, 5, 0.0},    {{1.0, 1.0, 0.5}, 6, 0.3},
                        {{0.25, 0.25, 1.0}, 8, 0.0},  {{0.25, 0.125, 1.0}, 8, 0.0},
                        {{1.0, 1.0, 0.125}, 12, 0.0}, {{1.0, 1.0, 0.125}, 12, 0.3}, {{0.89, 0.89, 1.0}, 3, 0.0}};
  const double c[3] = {0.5, -1.0, 2.0};
  for (const Case &cs : cases) {
    Points p = slab_points(400, 63, c, 1.5, cs.shape, cs.shift);
    const Reference ref = slab_reference(slab_options(6, cs.k, c, 1.5, cs.shape), p);
    for (int order : {6, 9}) {
      const SlabErrors e = slab_errors(slab_options(order, cs.k, c, 1.5, cs.shape), p, ref);
      std::printf("  slab grid k=%d box %.2f %.2f %.2f net %.1f p=%d: pot %.2e grad %.2e\n", cs.k, cs.shape[0],
                  cs.shape[1], cs.shape[2], cs.shift, order, e.pot, e.grad);
      EXPECT_LT(e.grad, order == 6 ? 3e-5 : 3e-7);
      EXPECT_LT(e.pot, order == 6 ? 3e-5 : 3e-7);
    }
  }
}

TEST(PeriodicSlab, LayerOnTheFloor)
{
  // a dense layer at the bottom of a tall cell (a sediment): most cells empty
  const double c[3] = {0, 0, 0}, shape[3] = {1.0, 1.0, 1.0};
  Points p = slab_points(600, 64, c, 1.0, shape);
  for (std::size_t i = 0; i < p.size(); ++i) p.xyz[3 * i + 2] = -1.0 + 0.1 * (p.xyz[3 * i + 2] + 1.0);
  const kifmm::Options o = slab_options(8, 5, c, 1.0, shape);
  const SlabErrors e = slab_errors(o, p, slab_reference(o, p));
  std::printf("  slab grid floor layer p=8: pot %.2e grad %.2e\n", e.pot, e.grad);
  EXPECT_LT(e.grad, 1e-6);
}

// The grid of a slab chosen from the points (choose_tree on the actual cell occupancies, open in
// z): uniform points get a grid next to the uniform model's; a heap of sediment on 1/16 of the
// floor fills few cells densely, so the choice takes more cells (fewer points per cell) than the
// uniform model of the same N, at a lower modelled cost on those points, and it meets the
// accuracy there. (A layer over the whole floor changes the in-plane occupancy little: cells
// are nearly cubic, so there the choice is the uniform one.) plan_tree asks for the choice from
// the points on one process only.
TEST(PeriodicSlab, GridChosenFromTheOccupancies)
{
  const double c[3] = {0, 0, 0}, shape[3] = {1.0, 1.0, 0.5};
  const std::size_t n = 20000;
  kifmm::Options o = slab_options(6, 0, c, 1.0, shape);
  const kifmm::TreeChoice u = kifmm::choose_slab_grid(6, n, shape);
  const Points flat = slab_points(n, 5, c, 1.0, shape);
  const kifmm::TreeChoice cu = kifmm::choose_tree(KernelSpec{}, o, n, flat.xyz.data());
  EXPECT_LE(std::abs(cu.grid - u.grid), 1) << "uniform points: " << cu.grid << " against the model's " << u.grid;
  Points sed = slab_points(n, 6, c, 1.0, shape);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = (sed.xyz[3 * i + 2] + 0.5);    // in [0, 1): a layer dense at the floor
    sed.xyz[3 * i + 2] = -0.5 + 0.1 * r * r;
    for (int d = 0; d < 2; ++d) sed.xyz[3 * i + d] = -1.0 + 0.25 * (sed.xyz[3 * i + d] + 1.0);    // on 1/16 of it
  }
  const kifmm::TreeChoice cs = kifmm::choose_tree(KernelSpec{}, o, n, sed.xyz.data());
  auto cost_on_sediment = [&](int k) {
    return kifmm::modelled_grid_cost(6, n, kifmm::grid_counts(n, sed.xyz.data(), c, 1.0, k, shape, true));
  };
  std::printf("  slab 1 x 1 x 0.5, %zu points, order 6: uniform model grid %d; from uniform points %d; "
              "heap %d (modelled %.3g s, the uniform model's grid %.3g s)\n",
              n, u.grid, cu.grid, cs.grid, cs.cost, cost_on_sediment(u.grid));
  EXPECT_GT(cs.grid, u.grid);
  EXPECT_NEAR(cs.cost, cost_on_sediment(cs.grid), 1e-12 * cs.cost);
  EXPECT_LT(cs.cost, 0.9 * cost_on_sediment(u.grid));
  for (int k = 3; k <= kifmm::max_grid_cells_long(6, shape); ++k)
    if (kifmm::grid_fits_cell(6, k, shape, true)) EXPECT_GE(cost_on_sediment(k), cs.cost) << "grid " << k;
  // the chosen grid meets order 6's accuracy on the heap (a smaller sample of it)
  const std::size_t m = 800;
  Points few = sed;
  few.xyz.resize(3 * m);
  few.q.resize(m);
  few = neutral(few);
  kifmm::Options chosen = o;
  chosen.periodic_grid = cs.grid;
  const SlabErrors e = slab_errors(chosen, few, slab_reference(chosen, few));
  EXPECT_LT(e.grad, 1e-4);
  // plan_tree: from the points (on several ranks their stand-in, up to its size), with the grid
  // in use kept until then
  const kifmm::TreePlan one = kifmm::plan_tree(o, kifmm::TreeRequest{n, 0, -1, false});
  EXPECT_TRUE(one.from_points);
  EXPECT_EQ(one.options.periodic_grid, u.grid);
  EXPECT_TRUE(kifmm::plan_tree(o, kifmm::TreeRequest{n, 0, -1, true}).from_points);
  EXPECT_FALSE(kifmm::plan_tree(o, kifmm::TreeRequest{kifmm::kLayoutMaxPoints + 1, 0, -1, true}).from_points);
  EXPECT_FALSE(kifmm::plan_tree(o, kifmm::TreeRequest{n, 0, 7, false}).from_points);
  kifmm::Options current = o;
  current.periodic_grid = cs.grid;
  EXPECT_EQ(kifmm::plan_tree(o, kifmm::TreeRequest{n, 0, -1, false}, &current).options.periodic_grid, cs.grid);
}

TEST(PeriodicSlab, WhatIsNotSupportedThrows)
{
  const double c[3] = {0, 0, 0}, shape[3] = {1.0, 1.0, 0.5};
  Points p = slab_points(200, 65, c, 1.0, shape);
  std::vector<double> g(3 * p.size());
  auto eval = [&](const kifmm::Options &o, const KernelSpec &k = KernelSpec{}) {
    kifmm::make_evaluator(k, o)->evaluate(p.size(), p.xyz.data(), p.q.data(), p.size(), p.xyz.data(), nullptr,
                                           g.data());
  };
  EXPECT_THROW(eval(slab_options(6, 0, c, 1.0, shape)), std::invalid_argument);    // the octree
  EXPECT_THROW(eval(slab_options(6, 6, c, 1.0, shape), KernelSpec{KernelType::Yukawa, 2.0}), std::invalid_argument);
  Points out = p;
  out.xyz[2] = 0.6;    // above the slab's z extent
  std::vector<double> g2(3 * out.size());
  EXPECT_THROW(kifmm::make_evaluator(KernelSpec{}, slab_options(6, 6, c, 1.0, shape))
                   ->evaluate(out.size(), out.xyz.data(), out.q.data(), out.size(), out.xyz.data(), nullptr, g2.data()),
               std::invalid_argument);
}
