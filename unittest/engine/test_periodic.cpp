// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic boundaries of the engine (periodic.h): lattice sums, periodic lists, FMM against
// the Ewald reference sum, wrapping, scaling with the cell size.
#include "periodic.h"

#include "fmm_core.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <tuple>

using kifmm::KernelSpec;
using kifmm::KernelType;
using namespace kifmm_test;

namespace {

struct PerErrors {
  double pot, grad;
};

PerErrors periodic_errors(const KernelSpec &k, const kifmm::Options &o, const Points &p, Reference *ref_out = nullptr)
{
  const std::size_t n = p.size();
  std::vector<double> pot(n), g(3 * n), rp(n), rg(3 * n);
  kifmm::make_evaluator(k, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
  kifmm::periodic_direct_sum(k, o.root_center, o.root_half_width, n, p.xyz.data(), p.q.data(), n, p.xyz.data(),
                             rp.data(), rg.data());
  if (ref_out) *ref_out = Reference{rp, rg};
  return {rel_l2(pot, rp), rel_l2(g, rg)};
}

// ---------------------------------------------------------------- lattice sums

TEST(Periodic, LaplaceRegularPartAtZeroIsTheWignerConstant)
{
  // lim_{r->0} (G_per(r) - 1/r) = -2.837297479480620 / L for a cubic lattice (tin-foil, with
  // the uniform background); unit cell L = 2
  const double r[3] = {0, 0, 0};
  double v, g[3];
  kifmm::periodic_green_unit(KernelSpec{}, r, true, v, g);
  EXPECT_NEAR(v, -2.837297479480619 / 2.0, 3e-14);
}

TEST(Periodic, LaplaceGreenIsPeriodicAndSymmetric)
{
  const double r[3] = {0.3, -0.45, 0.7}, rs[3] = {0.3 + 2.0, -0.45 - 2.0, 0.7 + 4.0}, rm[3] = {-0.3, 0.45, -0.7};
  double v, vs, vm, g[3], gs[3], gm[3];
  kifmm::periodic_green_unit(KernelSpec{}, r, false, v, g);
  kifmm::periodic_green_unit(KernelSpec{}, rs, false, vs, gs);
  kifmm::periodic_green_unit(KernelSpec{}, rm, false, vm, gm);
  EXPECT_NEAR(v, vs, 1e-13);
  EXPECT_NEAR(v, vm, 1e-14);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(g[d], gs[d], 1e-12);
    EXPECT_NEAR(g[d], -gm[d], 1e-13);
  }
  // gradient = derivative of the value
  const double e = 1e-5;
  for (int d = 0; d < 3; ++d) {
    double a[3] = {r[0], r[1], r[2]}, b[3] = {r[0], r[1], r[2]}, va, vb, t[3];
    a[d] += e;
    b[d] -= e;
    kifmm::periodic_green_unit(KernelSpec{}, a, false, va, t);
    kifmm::periodic_green_unit(KernelSpec{}, b, false, vb, t);
    EXPECT_NEAR((va - vb) / (2 * e), g[d], 1e-8);
  }
}

TEST(Periodic, YukawaEwaldSplitEqualsDirectLatticeSum)
{
  // screened Ewald (kappa < 10 in unit-cell coordinates) against the absolutely convergent
  // image sum (images up to |n| = 12, exp(-kappa 24) negligible)
  for (double kappa : {1.5, 4.0, 9.0}) {
    const double r[3] = {0.4, -0.25, 0.9};
    double v, g[3];
    kifmm::periodic_green_unit(KernelSpec{KernelType::Yukawa, kappa}, r, false, v, g);
    double bv = 0, bg[3] = {0, 0, 0};
    for (int nx = -12; nx <= 12; ++nx)
      for (int ny = -12; ny <= 12; ++ny)
        for (int nz = -12; nz <= 12; ++nz) {
          const double d[3] = {r[0] + 2.0 * nx, r[1] + 2.0 * ny, r[2] + 2.0 * nz};
          const double rr = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
          const double e = std::exp(-kappa * rr);
          bv += e / rr;
          for (int k = 0; k < 3; ++k) bg[k] += -e * (1 + kappa * rr) / (rr * rr * rr) * d[k];
        }
    EXPECT_NEAR(v, bv, 5e-14 * std::fabs(bv) + 1e-15) << kappa;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(g[k], bg[k], 1e-13 * std::fabs(bv) + 1e-15) << kappa;
  }
}

// ---------------------------------------------------------------- lists

TEST(Periodic, ListsCoverEveryLeafPairAndNearImageExactlyOnce)
{
  // adaptive tree (clustered + uniform); for every target leaf B, source leaf A and root
  // shift n in {-1,0,1}^3, exactly one entry (C, n) of U, W, X of B or of V, X of an
  // ancestor of B has A inside C (C = A or an ancestor of A)
  Points p = uniform_cube(1500, 3);
  Points c = two_clusters(1500, 4);
  for (std::size_t i = 0; i < c.size(); ++i) {
    for (int d = 0; d < 3; ++d) p.xyz.push_back(0.2 * c.xyz[3 * i + d] / 5.0 + (d == 0 ? 0.0 : 0.9));
    p.q.push_back(c.q[i]);
  }
  kifmm::Octree tree;
  kifmm::RootBox root;
  root.half_width = 1.0;
  kifmm::build_octree(tree, root, p.size(), p.xyz.data(), p.size(), p.xyz.data(), 20, 20);
  kifmm::InteractionLists lists;
  kifmm::PeriodicImageLists img;
  kifmm::build_periodic_interaction_lists(tree, lists, img);
  ASSERT_GE(tree.depth, 5);
  const auto &cells = tree.cells;
  auto code = [](const signed char *s) { return (s[0] + 1) * 9 + (s[1] + 1) * 3 + (s[2] + 1); };
  // (target leaf, source leaf, shift) -> count
  std::map<std::tuple<int, int, int>, int> count;
  std::vector<int> src_leaves;
  for (int l : tree.leaves)
    if (cells[l].n_src() > 0) src_leaves.push_back(l);
  auto leaves_under = [&](int c, std::vector<int> &out) {
    std::vector<int> st{c};
    while (!st.empty()) {
      int x = st.back();
      st.pop_back();
      if (cells[x].leaf()) {
        if (cells[x].n_src() > 0) out.push_back(x);
      } else
        for (int k = 0; k < cells[x].n_children; ++k) st.push_back(cells[x].first_child + k);
    }
  };
  for (int b : tree.leaves) {
    if (cells[b].n_trg() == 0) continue;
    std::vector<std::pair<int, int>> entries;    // (cell, shift code)
    for (const int *a = lists.U.begin(b); a != lists.U.end(b); ++a) entries.push_back({*a, 13});
    for (const int *a = lists.W.begin(b); a != lists.W.end(b); ++a) entries.push_back({*a, 13});
    for (int e = img.U.begin(b); e < img.U.end(b); ++e) entries.push_back({img.U.idx[e], code(img.U.shift_of(e))});
    for (int e = img.W.begin(b); e < img.W.end(b); ++e) entries.push_back({img.W.idx[e], code(img.W.shift_of(e))});
    for (int c = b; c >= 0; c = cells[c].parent) {
      for (int e = lists.V.off[c]; e < lists.V.off[c + 1]; ++e)
        entries.push_back({lists.V.idx[e], code(&img.V_shift[3 * (std::size_t) e])});
      for (const int *a = lists.X.begin(c); a != lists.X.end(c); ++a) entries.push_back({*a, 13});
      for (int e = img.X.begin(c); e < img.X.end(c); ++e) entries.push_back({img.X.idx[e], code(img.X.shift_of(e))});
    }
    for (auto [c, s] : entries) {
      std::vector<int> ls;
      leaves_under(c, ls);
      for (int a : ls) ++count[{b, a, s}];
    }
    for (int a : src_leaves)
      for (int s = 0; s < 27; ++s) {
        auto it = count.find({b, a, s});
        const int n = it == count.end() ? 0 : it->second;
        ASSERT_EQ(n, 1) << "target leaf " << b << " source leaf " << a << " shift " << s;
      }
  }
}

// ---------------------------------------------------------------- FMM vs Ewald

TEST(Periodic, LaplaceNeutralMatchesEwald)
{
  Points p = neutral(uniform_cube(3000, 21));
  double prev = 1;
  for (int order : {4, 6, 8, 10, 12, 14}) {
    PerErrors e = periodic_errors(KernelSpec{}, periodic_options(order, 40), p);
    std::printf("  periodic laplace p=%2d: pot %.2e grad %.2e\n", order, e.pot, e.grad);
    EXPECT_LT(e.grad, order >= 12 ? 1e-9 : prev);
    EXPECT_LT(e.pot, 10 * e.grad + 1e-12);
    prev = e.grad;
  }
}

TEST(Periodic, LaplaceNonNeutralIncludesTheBackground)
{
  Points p = uniform_cube(2000, 22);
  for (double &q : p.q) q += 0.3;    // net charge
  const double c[3] = {0.5, -2.0, 10.0};
  for (double &x : p.xyz) x *= 1.5;
  for (int order : {6, 12}) {
    PerErrors e = periodic_errors(KernelSpec{}, periodic_options(order, 40, 1.5, c), p);
    std::printf("  periodic laplace non-neutral p=%2d: pot %.2e grad %.2e\n", order, e.pot, e.grad);
    EXPECT_LT(e.pot, order == 6 ? 1e-4 : 1e-9);
    EXPECT_LT(e.grad, order == 6 ? 1e-4 : 1e-9);
  }
}

TEST(Periodic, DipolesAndClustersMatchEwald)
{
  Points d = dipoles(1500, 23);
  PerErrors e = periodic_errors(KernelSpec{}, periodic_options(12, 40), d);
  std::printf("  periodic dipoles p=12: pot %.2e grad %.2e\n", e.pot, e.grad);
  EXPECT_LT(e.grad, 1e-8);
  // a dense cluster near a corner of the cell: its images are close to it across the faces
  Points c = gaussian_cluster(3000, 0.97, 0.03, 5);    // wrapped by the engine
  e = periodic_errors(KernelSpec{}, periodic_options(12, 30), c);
  std::printf("  periodic corner cluster p=12: pot %.2e grad %.2e\n", e.pot, e.grad);
  EXPECT_LT(e.grad, 1e-8);
}

TEST(Periodic, YukawaMatchesLatticeSum)
{
  Points p = uniform_cube(2000, 24);
  // kappa h = 1.5 and 6 (screened Ewald table), 15 (direct image table)
  for (double kappa : {1.5, 6.0, 15.0}) {
    PerErrors e = periodic_errors(KernelSpec{KernelType::Yukawa, kappa}, periodic_options(10, 40), p);
    std::printf("  periodic yukawa kappa %4.1f p=10: pot %.2e grad %.2e\n", kappa, e.pot, e.grad);
    EXPECT_LT(e.pot, 1e-7);
    EXPECT_LT(e.grad, 1e-7);
  }
}

TEST(Periodic, RootLeafAndFewPoints)
{
  Points p = uniform_cube(7, 25);
  PerErrors e = periodic_errors(KernelSpec{}, periodic_options(12, 64), p);
  EXPECT_LT(e.grad, 1e-9);
  EXPECT_LT(e.pot, 1e-9);
}

TEST(Periodic, PointsOutsideTheCellAreWrapped)
{
  Points p = neutral(uniform_cube(1000, 26));
  Points s = p;
  for (std::size_t i = 0; i < s.size(); i += 3) s.xyz[3 * i + (i % 3)] += (i % 2 ? 2.0 : -4.0);
  const std::size_t n = p.size();
  auto o = periodic_options(8, 32);
  std::vector<double> a(n), ga(3 * n), b(n), gb(3 * n);
  kifmm::make_evaluator(KernelSpec{}, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), a.data(), ga.data());
  kifmm::make_evaluator(KernelSpec{}, o)->evaluate(n, s.xyz.data(), s.q.data(), n, s.xyz.data(), b.data(), gb.data());
  EXPECT_LT(rel_l2(b, a), 1e-13);
  EXPECT_LT(rel_l2(gb, ga), 1e-13);
}

TEST(Periodic, CellSizeScaling)
{
  // Laplace: scaling positions and cell by s scales potentials by 1/s and gradients by 1/s^2
  // (the lattice operator is computed once at unit size); set_root changes the cell
  Points p = neutral(uniform_cube(2000, 27));
  const std::size_t n = p.size();
  auto ev = kifmm::make_evaluator(KernelSpec{}, periodic_options(8, 40));
  std::vector<double> a(n), ga(3 * n), b(n), gb(3 * n);
  ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), a.data(), ga.data());
  const double s = 2.75, c[3] = {3.0, 3.0, 3.0};
  for (double &x : p.xyz) x = 3.0 + s * x;
  ev->set_root(c, s);
  ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), b.data(), gb.data());
  for (double &v : b) v *= s;
  for (double &v : gb) v *= s * s;
  EXPECT_LT(rel_l2(b, a), 1e-12);
  EXPECT_LT(rel_l2(gb, ga), 1e-12);
}

TEST(Periodic, RequiresFixedRoot)
{
  kifmm::Options o;
  o.periodic = true;
  Points p = uniform_cube(10, 1);
  auto ev = kifmm::make_evaluator(KernelSpec{}, o);
  std::vector<double> g(30);
  EXPECT_THROW(ev->evaluate(10, p.xyz.data(), p.q.data(), 10, p.xyz.data(), nullptr, g.data()), std::invalid_argument);
}

// Same source and target points: the near field runs pair by pair for both leaves
// (p2p_mutual.h) and the levels 1-2 M2L with summed slot kernels. A permuted copy of the
// targets gives the same tree but the one-sided near field: equal up to rounding. Two
// coincident points are counted as coincident pairs in both paths. Laplace and Yukawa,
// adaptive (clustered) and uniform trees, with and without the potential.
TEST(Periodic, MutualNearFieldEqualsOneSided)
{
  Points p = neutral(two_clusters(4000, 30));
  p.xyz[3] = p.xyz[0], p.xyz[4] = p.xyz[1], p.xyz[5] = p.xyz[2];    // points 0 and 1 coincide
  Points u = neutral(uniform_cube(3000, 31));
  const std::size_t n = p.size();
  const std::vector<std::pair<const Points *, KernelSpec>> cases = {
      {&p, KernelSpec{}}, {&u, KernelSpec{}}, {&u, KernelSpec{KernelType::Yukawa, 2.0}}};
  for (const auto &[pts, k] : cases) {
    const std::size_t m = pts->size();
    std::vector<std::size_t> perm(m);
    for (std::size_t i = 0; i < m; ++i) perm[i] = (i * 7919) % m;    // m not a multiple of 7919
    std::vector<double> txyz(3 * m);
    for (std::size_t i = 0; i < m; ++i)
      for (int d = 0; d < 3; ++d) txyz[3 * i + d] = pts->xyz[3 * perm[i] + d];
    auto ev = kifmm::make_evaluator(k, periodic_options(6, 40));
    std::vector<double> pm(m), gm(3 * m), po(m), go(3 * m), gn(3 * m), g1(3 * m);
    ev->evaluate(m, pts->xyz.data(), pts->q.data(), m, pts->xyz.data(), pm.data(), gm.data());
    const std::size_t zeros_mutual = ev->stats().coincident_pairs;
    ev->evaluate(m, pts->xyz.data(), pts->q.data(), m, pts->xyz.data(), nullptr, gn.data());
    ev->evaluate(m, pts->xyz.data(), pts->q.data(), m, txyz.data(), po.data(), go.data());
    const std::size_t zeros_one = ev->stats().coincident_pairs;
    std::vector<double> pb(m), gb(3 * m);    // back to the input order
    for (std::size_t i = 0; i < m; ++i) {
      pb[perm[i]] = po[i];
      for (int d = 0; d < 3; ++d) gb[3 * perm[i] + d] = go[3 * i + d];
    }
    EXPECT_LT(rel_l2(pm, pb), 1e-13);
    EXPECT_LT(rel_l2(gm, gb), 1e-13);
    EXPECT_LT(rel_l2(gn, gm), 1e-15);
    EXPECT_EQ(zeros_mutual, pts == &p ? 2u : 0u);
    EXPECT_EQ(zeros_one, pts == &p ? 2u + n : 0u + m);    // distinct arrays: self pairs count
    // one and two threads: the same bits
    const int saved = omp_get_max_threads();
    omp_set_num_threads(saved == 1 ? 2 : 1);
    kifmm::make_evaluator(k, periodic_options(6, 40))
        ->evaluate(m, pts->xyz.data(), pts->q.data(), m, pts->xyz.data(), nullptr, g1.data());
    omp_set_num_threads(saved);
    EXPECT_EQ(g1, gn);
  }
}

// The cost relative to free space is measured by bench/bench_periodic (CPU time, both modes
// timed alternately; doc/kspace_kifmm.rst), not here: timings depend on the machine's load.

}    // namespace
