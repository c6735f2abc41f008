// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic boundaries in rectangular (orthogonal, non-cubic) cells: the Ewald reference of a
// rectangular lattice against the cubic one of replicated points, the FMM against that
// reference (Laplace, net charge, Yukawa), boxes that change shape, what stays cubic-only.
#include "periodic.h"

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

// Points uniform in the box [c - h shape, c + h shape) (charges in [-1, 1] plus `shift`).
Points box_points(std::size_t n, unsigned seed, const double c[3], double h, const double shape[3], double shift = 0)
{
  Points p = uniform_cube(n, seed);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] = c[d] + h * shape[d] * p.xyz[3 * i + d];
    p.q[i] += shift;
  }
  return p;
}

kifmm::Options box_options(int order, int leaf, const double c[3], double h, const double shape[3])
{
  kifmm::Options o = periodic_options(order, leaf, h, c);
  for (int d = 0; d < 3; ++d) o.root_shape[d] = shape[d];
  return o;
}

struct BoxErrors {
  double pot, grad;
};

BoxErrors box_errors(const KernelSpec &k, const kifmm::Options &o, const Points &p)
{
  const std::size_t n = p.size();
  std::vector<double> pot(n), g(3 * n), rp(n), rg(3 * n);
  kifmm::make_evaluator(k, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
  kifmm::periodic_direct_sum(k, o.root_center, o.root_half_width, n, p.xyz.data(), p.q.data(), n, p.xyz.data(),
                             rp.data(), rg.data(), o.root_shape);
  return {rel_l2(pot, rp), rel_l2(g, rg)};
}

}    // namespace

// ---------------------------------------------------------------- the reference

TEST(PeriodicBox, RectangularEwaldEqualsTheCubeOfReplicas)
{
  // the cell of half-widths (1, 1/2, 1/4) tiles the cube of half-width 1 with 1 x 2 x 4 copies:
  // the cubic lattice sum of the replicated sources equals the rectangular one (net charge:
  // same charge density, the same uniform background)
  const double shape[3] = {1.0, 0.5, 0.25}, c[3] = {0.0, -0.5, -0.75};
  Points p = box_points(150, 41, c, 1.0, shape, 0.2);
  Points rep;
  for (int j = 0; j < 2; ++j)
    for (int l = 0; l < 4; ++l)
      for (std::size_t i = 0; i < p.size(); ++i) {
        rep.xyz.push_back(p.xyz[3 * i]);
        rep.xyz.push_back(p.xyz[3 * i + 1] + 1.0 * j);
        rep.xyz.push_back(p.xyz[3 * i + 2] + 0.5 * l);
        rep.q.push_back(p.q[i]);
      }
  const double c0[3] = {0, 0, 0};
  for (const KernelSpec &k : {KernelSpec{}, KernelSpec{KernelType::Yukawa, 2.0}, KernelSpec{KernelType::Yukawa, 14.0}}) {
    const std::size_t n = p.size();
    std::vector<double> a(n), ga(3 * n), b(n), gb(3 * n);
    kifmm::periodic_direct_sum(k, c, 1.0, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), a.data(), ga.data(), shape);
    kifmm::periodic_direct_sum(k, c0, 1.0, rep.size(), rep.xyz.data(), rep.q.data(), n, p.xyz.data(), b.data(),
                               gb.data());
    EXPECT_LT(rel_l2(a, b), 1e-12) << (int) k.type << " " << k.kappa;
    EXPECT_LT(rel_l2(ga, gb), 1e-12) << (int) k.type << " " << k.kappa;
  }
}

TEST(PeriodicBox, GreenIsPeriodicAlongEveryAxisAndItsGradientIsTheDerivative)
{
  const double shape[3] = {0.6, 1.0, 0.8};
  const double r[3] = {0.21, -0.37, 0.55};
  double v, g[3];
  kifmm::periodic_green_unit(KernelSpec{}, r, false, v, g, shape);
  for (int d = 0; d < 3; ++d) {
    double rs[3] = {r[0], r[1], r[2]}, vs, gs[3];
    rs[d] += 2.0 * shape[d];
    kifmm::periodic_green_unit(KernelSpec{}, rs, false, vs, gs, shape);
    EXPECT_NEAR(vs, v, 1e-12);
    const double mr[3] = {-r[0], -r[1], -r[2]};
    kifmm::periodic_green_unit(KernelSpec{}, mr, false, vs, gs, shape);
    EXPECT_NEAR(vs, v, 1e-12);
    // central difference of the value
    const double e = 1e-5;
    double rp[3] = {r[0], r[1], r[2]}, rm[3] = {r[0], r[1], r[2]}, vp, vm, t[3];
    rp[d] += e;
    rm[d] -= e;
    kifmm::periodic_green_unit(KernelSpec{}, rp, false, vp, t, shape);
    kifmm::periodic_green_unit(KernelSpec{}, rm, false, vm, t, shape);
    EXPECT_NEAR((vp - vm) / (2 * e), g[d], 1e-7);
  }
}

// ---------------------------------------------------------------- FMM against the reference

TEST(PeriodicBox, OctreeInNearlyCubicCells)
{
  // cells within max_cell_aspect of a cube: the octree (every cell has the box's shape), errors
  // within a few times those of a cube (cube, these points: 6e-6, 2e-7, 2e-10 at orders 6, 9, 12)
  const double shapes[2][3] = {{1.0, 0.97, 0.96}, {0.96, 1.0, 0.98}};
  const double c[3] = {2.0, -1.0, 0.5};
  for (const auto &shape : shapes) {
    ASSERT_TRUE(kifmm::octree_fits_cell(shape));
    Points p = neutral(box_points(2500, 42, c, 1.5, shape));
    for (int order : {6, 9, 12}) {
      const BoxErrors e = box_errors(KernelSpec{}, box_options(order, 40, c, 1.5, shape), p);
      std::printf("  octree box %.2f %.2f %.2f p=%2d: pot %.2e grad %.2e\n", shape[0], shape[1], shape[2], order,
                  e.pot, e.grad);
      EXPECT_LT(e.grad, order == 6 ? 2e-5 : order == 9 ? 2e-7 : 1e-9);
      EXPECT_LT(e.pot, 10 * e.grad + 1e-12);
    }
  }
  const double flat[3] = {1.0, 1.0, 0.9};
  EXPECT_FALSE(kifmm::octree_fits_cell(flat));
}

TEST(PeriodicBox, GridInRectangularBoxesUpToOneToEight)
{
  // boxes the octree does not fit: the single-level grid of nearly cubic cells, any aspect
  // ratio (here up to 8: a needle and a slab), orders 6 and 9
  struct Case {
    double shape[3];
    int k;    // cells along the longest axis
  };
  const Case cases[] = {{{1.0, 0.5, 0.5}, 6}, {{1.0, 0.8, 0.6}, 5}, {{0.6, 0.8, 1.0}, 10},
                        {{1.0, 0.125, 0.125}, 24}, {{1.0, 1.0, 0.125}, 24}};
  const double c[3] = {0.5, 0.0, -2.0};
  for (const Case &cs : cases) {
    ASSERT_TRUE(kifmm::grid_fits_cell(6, cs.k, cs.shape)) << cs.k;
    Points p = neutral(box_points(2000, 43, c, 2.0, cs.shape));
    for (int order : {6, 9}) {
      kifmm::Options o = box_options(order, 40, c, 2.0, cs.shape);
      o.periodic_grid = cs.k;
      const BoxErrors e = box_errors(KernelSpec{}, o, p);
      std::printf("  grid k=%2d box %.3f %.3f %.3f p=%d: pot %.2e grad %.2e\n", cs.k, cs.shape[0], cs.shape[1],
                  cs.shape[2], order, e.pot, e.grad);
      EXPECT_LT(e.grad, order == 6 ? 2e-5 : 2e-7);
      EXPECT_LT(e.pot, 10 * e.grad + 1e-12);
    }
  }
}

TEST(PeriodicBox, GridWithOneOrTwoCellsAcrossAThinSide)
{
  // thin sides of 1 cell (the cell's near field holds its own images) or 2 cells (one
  // neighbour met at two shifts): sources = targets (mutual near field) and separate targets
  // (one-sided), Laplace and Yukawa, against the Ewald sum
  struct Case {
    double shape[3];
    int k;
    int cells[3];
  };
  const Case cases[] = {{{1.0, 1.0, 0.125}, 8, {8, 8, 1}},
                        {{1.0, 0.125, 0.125}, 16, {16, 2, 2}},
                        {{0.25, 1.0, 0.125}, 8, {2, 8, 1}},
                        {{1.0, 0.125, 0.125}, 8, {8, 1, 1}}};
  const double c[3] = {0.5, 0.0, -2.0};
  for (const Case &cs : cases) {
    int kd[3];
    kifmm::grid_cells_per_axis(cs.k, cs.shape, kd);
    for (int d = 0; d < 3; ++d) ASSERT_EQ(kd[d], cs.cells[d]);
    ASSERT_TRUE(kifmm::grid_fits_cell(8, cs.k, cs.shape)) << cs.k;
    const Points p = neutral(box_points(800, 52, c, 2.0, cs.shape));
    const Points t = box_points(200, 53, c, 2.0, cs.shape);
    for (const KernelSpec &ker : {KernelSpec{}, KernelSpec{KernelType::Yukawa, 2.0}}) {
      kifmm::Options o = box_options(8, 40, c, 2.0, cs.shape);
      o.periodic_grid = cs.k;
      const BoxErrors e = box_errors(ker, o, p);
      // one-sided: separate targets
      const std::size_t n = p.size(), m = t.size();
      std::vector<double> pot(m), g(3 * m), rp(m), rg(3 * m);
      kifmm::make_evaluator(ker, o)->evaluate(n, p.xyz.data(), p.q.data(), m, t.xyz.data(), pot.data(), g.data());
      kifmm::periodic_direct_sum(ker, o.root_center, o.root_half_width, n, p.xyz.data(), p.q.data(), m, t.xyz.data(),
                                 rp.data(), rg.data(), o.root_shape);
      const double eg = rel_l2(g, rg), ep = rel_l2(pot, rp);
      std::printf("  grid %dx%dx%d %s p=8: mutual pot %.2e grad %.2e, one-sided pot %.2e grad %.2e\n", kd[0], kd[1],
                  kd[2], ker.type == KernelType::Yukawa ? "yukawa" : "laplace", e.pot, e.grad, ep, eg);
      EXPECT_LT(e.grad, 2e-6);
      EXPECT_LT(e.pot, 2e-6);
      EXPECT_LT(eg, 2e-6);
      EXPECT_LT(ep, 2e-6);
    }
  }
}

TEST(PeriodicBox, NetChargeAndPointsOutsideTheCell)
{
  const double shape[3] = {0.6, 0.8, 1.0}, c[3] = {0.0, 3.0, -1.0};
  Points p = box_points(2000, 44, c, 1.0, shape, 0.3);
  // a third of the points moved by whole periods (and beyond): the engine wraps them
  Points s = p;
  for (std::size_t i = 0; i < s.size(); i += 3) s.xyz[3 * i + i % 3] += 2.0 * shape[i % 3] * (i % 2 ? 1.0 : -2.0);
  kifmm::Options o = box_options(9, 40, c, 1.0, shape);
  o.periodic_grid = 10;
  const BoxErrors e = box_errors(KernelSpec{}, o, s);
  std::printf("  grid box net charge p=9: pot %.2e grad %.2e\n", e.pot, e.grad);
  EXPECT_LT(e.pot, 1e-6);
  EXPECT_LT(e.grad, 1e-6);
  // the same points through the octree in a nearly cubic cell
  const double near[3] = {1.0, 0.98, 0.96};
  Points q = box_points(2000, 45, c, 1.0, near, 0.3);
  for (std::size_t i = 0; i < q.size(); i += 4) q.xyz[3 * i + i % 3] -= 2.0 * near[i % 3];
  const BoxErrors f = box_errors(KernelSpec{}, box_options(10, 40, c, 1.0, near), q);
  std::printf("  octree box net charge p=10: pot %.2e grad %.2e\n", f.pot, f.grad);
  EXPECT_LT(f.pot, 2e-7);
  EXPECT_LT(f.grad, 2e-7);
}

TEST(PeriodicBox, YukawaMatchesLatticeSum)
{
  const double shape[3] = {1.0, 0.5, 0.5}, near[3] = {0.97, 1.0, 0.98}, c[3] = {0, 0, 0};
  Points p = box_points(1500, 46, c, 1.0, shape);
  Points q = box_points(1500, 47, c, 1.0, near);
  for (double kappa : {1.5, 6.0, 15.0}) {
    const KernelSpec k{KernelType::Yukawa, kappa};
    kifmm::Options o = box_options(9, 40, c, 1.0, shape);
    o.periodic_grid = 6;
    const BoxErrors e = box_errors(k, o, p);
    const BoxErrors f = box_errors(k, box_options(9, 40, c, 1.0, near), q);
    std::printf("  yukawa kappa %4.1f p=9: grid box pot %.2e grad %.2e, octree box pot %.2e grad %.2e\n", kappa,
                e.pot, e.grad, f.pot, f.grad);
    EXPECT_LT(e.pot, 1e-6);
    EXPECT_LT(e.grad, 1e-6);
    EXPECT_LT(f.pot, 1e-6);
    EXPECT_LT(f.grad, 1e-6);
  }
}

TEST(PeriodicBox, ClusterAcrossTheShortFaces)
{
  // a dense cluster at a corner of a flat cell: its images are close across the short faces
  const double shape[3] = {1.0, 1.0, 0.5}, c[3] = {0, 0, 0};
  Points p = gaussian_cluster(3000, 0.97, 0.03, 48);
  kifmm::Options o = box_options(9, 30, c, 1.0, shape);
  o.periodic_grid = 6;
  const BoxErrors e = box_errors(KernelSpec{}, o, p);
  std::printf("  grid box corner cluster p=9: pot %.2e grad %.2e\n", e.pot, e.grad);
  EXPECT_LT(e.grad, 1e-6);
}

// ---------------------------------------------------------------- boxes that change

TEST(PeriodicBox, SetRootBoxFollowsAChangeOfShape)
{
  const double a[3] = {1.0, 0.98, 0.96}, b[3] = {0.97, 1.0, 0.99}, c[3] = {0, 0, 0};
  Points p = neutral(box_points(2000, 49, c, 1.0, a));
  const std::size_t n = p.size();
  for (int grid : {0, 5}) {
    kifmm::Options oa = box_options(8, 40, c, 1.0, a);
    oa.periodic_grid = grid;
    auto ev = kifmm::make_evaluator(KernelSpec{}, oa);
    std::vector<double> x(n), gx(3 * n), y(n), gy(3 * n);
    ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), x.data(), gx.data());
    // the same points in the new box (scaled per axis), through set_root_box
    Points q = p;
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) q.xyz[3 * i + d] *= 1.1 * b[d] / a[d];
    const double hw[3] = {1.1 * b[0], 1.1 * b[1], 1.1 * b[2]};
    ev->set_root_box(c, hw);
    EXPECT_DOUBLE_EQ(ev->options().root_half_width, 1.1);
    EXPECT_DOUBLE_EQ(ev->options().root_shape[1], 1.0);
    ev->evaluate(n, q.xyz.data(), q.q.data(), n, q.xyz.data(), x.data(), gx.data());
    kifmm::Options ob = box_options(8, 40, c, 1.1, b);
    ob.periodic_grid = grid;
    kifmm::make_evaluator(KernelSpec{}, ob)->evaluate(n, q.xyz.data(), q.q.data(), n, q.xyz.data(), y.data(), gy.data());
    EXPECT_LT(rel_l2(x, y), 1e-12) << grid;    // shape from the half-widths: to round-off
    EXPECT_LT(rel_l2(gx, gy), 1e-12) << grid;
    // and it is the right answer for the new box
    std::vector<double> rp(n), rg(3 * n);
    kifmm::periodic_direct_sum(KernelSpec{}, c, 1.1, n, q.xyz.data(), q.q.data(), n, q.xyz.data(), rp.data(),
                               rg.data(), b);
    EXPECT_LT(rel_l2(gx, rg), 2e-6) << grid;
  }
  // a cube through set_root_box is the cube of set_root
  auto ev = kifmm::make_evaluator(KernelSpec{}, box_options(8, 40, c, 1.0, a));
  const double cube[3] = {1.3, 1.3, 1.3};
  ev->set_root_box(c, cube);
  for (int d = 0; d < 3; ++d) EXPECT_EQ(ev->options().root_shape[d], 1.0);
}

TEST(PeriodicBox, CubeShapeIsTheCube)
{
  // root_shape 1 1 1 is exactly the cubic evaluation (same operators, same lattice table)
  const double one[3] = {1, 1, 1}, c[3] = {0, 0, 0};
  Points p = neutral(uniform_cube(1500, 50));
  const std::size_t n = p.size();
  for (int grid : {0, 4}) {
    std::vector<double> x(n), gx(3 * n), y(n), gy(3 * n);
    kifmm::Options o = box_options(7, 40, c, 1.0, one);
    o.periodic_grid = grid;
    kifmm::make_evaluator(KernelSpec{}, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), x.data(), gx.data());
    kifmm::make_evaluator(KernelSpec{}, periodic_options(7, 40, 1.0, nullptr, grid))
        ->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), y.data(), gy.data());
    EXPECT_EQ(x, y);
    EXPECT_EQ(gx, gy);
  }
}

TEST(PeriodicBox, GridOfStretchedCells)
{
  // cells longer than max_cell_aspect along some axis: cubic surfaces and a near field deeper
  // along the short axes (grid_near_depth): flat cells (12 x 12 x 2 in a 1 x 1 x 0.125 box,
  // 3 x 3 x 5 near cells), tall ones (10 x 10 x 1 there, 5 x 5 x 3), a needle (12 x 2 x 2) and
  // one cell across a thin side met at shifts up to 2 (12 x 12 x 1 in 1 x 1 x 0.06); sources =
  // targets (mutual near field) and separate targets (one-sided), Laplace and Yukawa, against
  // the Ewald sum: errors within the bounds of cubic cells at the same order
  struct Case {
    double shape[3];
    int k;
    int cells[3];
    int near[3];
  };
  const Case cases[] = {{{1.0, 1.0, 0.125}, 12, {12, 12, 2}, {1, 1, 2}},
                        {{1.0, 1.0, 0.125}, 10, {10, 10, 1}, {2, 2, 1}},
                        {{1.0, 0.125, 0.125}, 12, {12, 2, 2}, {1, 2, 2}},
                        {{1.0, 1.0, 0.06}, 12, {12, 12, 1}, {1, 1, 2}}};
  const double c[3] = {0.5, 0.0, -2.0};
  for (const Case &cs : cases) {
    int kd[3], m[3];
    double shp[3], ss[3];
    kifmm::grid_cells_per_axis(cs.k, cs.shape, kd);
    kifmm::grid_cell_shape(kd, cs.shape, shp);
    kifmm::grid_near_depth(shp, m, ss);
    for (int d = 0; d < 3; ++d) {
      ASSERT_EQ(kd[d], cs.cells[d]);
      ASSERT_EQ(m[d], cs.near[d]);
      ASSERT_EQ(ss[d], 1.0);
    }
    ASSERT_TRUE(kifmm::grid_fits_cell(8, cs.k, cs.shape)) << cs.k;
    const Points p = neutral(box_points(800, 54, c, 2.0, cs.shape));
    const Points t = box_points(100, 55, c, 2.0, cs.shape);
    const std::size_t n = p.size(), nt = t.size();
    for (const KernelSpec &ker : {KernelSpec{}, KernelSpec{KernelType::Yukawa, 2.0}}) {
      // the Ewald references (at the sources themselves, and at the separate targets)
      kifmm::Options o = box_options(6, 40, c, 2.0, cs.shape);
      o.periodic_grid = cs.k;
      std::vector<double> rp(n), rg(3 * n), rtp(nt), rtg(3 * nt);
      kifmm::periodic_direct_sum(ker, o.root_center, o.root_half_width, n, p.xyz.data(), p.q.data(), n, p.xyz.data(),
                                 rp.data(), rg.data(), o.root_shape);
      kifmm::periodic_direct_sum(ker, o.root_center, o.root_half_width, n, p.xyz.data(), p.q.data(), nt, t.xyz.data(),
                                 rtp.data(), rtg.data(), o.root_shape);
      for (int order : {6, 8}) {
        if (order == 8 && (ker.type == KernelType::Yukawa || &cs != &cases[0])) continue;    // (table cost)
        o.order = order;
        std::vector<double> pot(n), g(3 * n), tp(nt), tg(3 * nt);
        kifmm::make_evaluator(ker, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
        kifmm::make_evaluator(ker, o)->evaluate(n, p.xyz.data(), p.q.data(), nt, t.xyz.data(), tp.data(), tg.data());
        const double e[4] = {rel_l2(pot, rp), rel_l2(g, rg), rel_l2(tp, rtp), rel_l2(tg, rtg)};
        std::printf("  stretched grid %dx%dx%d (near %d %d %d) %s p=%d: mutual pot %.2e grad %.2e, one-sided pot "
                    "%.2e grad %.2e\n",
                    kd[0], kd[1], kd[2], m[0], m[1], m[2], ker.type == KernelType::Yukawa ? "yukawa" : "laplace",
                    order, e[0], e[1], e[2], e[3]);
        const double tol = order == 6 ? 2e-5 : 2e-6;    // as cubic cells (GridInRectangularBoxesUpToOneToEight)
        for (double v : e) EXPECT_LT(v, tol);
      }
    }
  }
}

TEST(PeriodicBox, TheChoiceTakesAGridWhoseCellsFit)
{
  const double shape[3] = {1.0, 0.8, 0.6}, c[3] = {0, 0, 0};
  Points p = box_points(4000, 51, c, 1.0, shape);
  kifmm::Options o = box_options(6, 40, c, 1.0, shape);
  for (std::size_t n : {300, 4000}) {
    const kifmm::TreeChoice t = kifmm::choose_tree(KernelSpec{}, o, n, p.xyz.data());
    EXPECT_TRUE(kifmm::grid_fits_cell(6, t.grid, shape)) << n << " " << t.grid;
    const kifmm::TreeChoice u = kifmm::choose_tree(6, n, true, true, shape);
    EXPECT_TRUE(kifmm::grid_fits_cell(6, u.grid, shape)) << n << " " << u.grid;
  }
  kifmm::TreeRequest req;
  req.n = p.size();
  req.grid = -1;
  const kifmm::TreePlan plan = kifmm::plan_tree(o, req);
  EXPECT_TRUE(kifmm::grid_fits_cell(6, plan.options.periodic_grid, shape));
  // and the chosen grid's evaluation is accurate
  kifmm::Options g = o;
  g.periodic_grid = plan.options.periodic_grid;
  const BoxErrors e = box_errors(KernelSpec{}, g, neutral(p));
  EXPECT_LT(e.grad, 5e-5);
  // a nearly cubic cell keeps the octree among the candidates
  const double near[3] = {1.0, 0.99, 0.98};
  EXPECT_TRUE(kifmm::octree_fits_cell(near));
  // no grid whose cells fit within memory (cells at most twice as long as wide along a side of
  // 0.005 need 100 along x, 30 along y): none returned
  const double awkward[3] = {1.0, 0.3, 0.005};
  for (int k = 3; k <= 400; ++k) EXPECT_FALSE(kifmm::grid_fits_cell(10, k, awkward)) << k;
  EXPECT_EQ(kifmm::choose_tree(10, 1000, true, true, awkward).grid, 0);
}
