// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// FMM vs direct sum: relative L2 errors of potential and gradient.
#include "test_util.h"

#include <gtest/gtest.h>

#include <cstdio>

using namespace kifmm_test;
using kifmm::KernelSpec;
using kifmm::KernelType;

namespace {
void report(const char *what, int order, const Errors &e)
{
  std::printf("  %-22s p=%2d  pot %.3e  grad %.3e\n", what, order, e.pot, e.grad);
}
}    // namespace

TEST(EngineAccuracy, EmptyAndTinyInputs)
{
  auto ev = kifmm::make_evaluator(KernelSpec{}, kifmm::Options{});
  ev->evaluate(0, nullptr, nullptr, 0, nullptr, nullptr, nullptr);
  EXPECT_EQ(ev->stats().n_targets, 0u);
  // one point: no interaction, exact zeros
  double x[3] = {0.1, 0.2, 0.3}, q = 2.0, pot = 7, g[3] = {7, 7, 7};
  ev->evaluate(1, x, &q, 1, x, &pot, g);
  EXPECT_EQ(pot, 0.0);
  EXPECT_EQ(g[0], 0.0);
  EXPECT_EQ(ev->stats().coincident_pairs, 0u);
  // no sources, some targets: zeros
  double t[6] = {0, 0, 0, 1, 1, 1}, p2[2] = {5, 5};
  ev->evaluate(0, nullptr, nullptr, 2, t, p2, nullptr);
  EXPECT_EQ(p2[0], 0.0);
  EXPECT_EQ(p2[1], 0.0);
  // two points: exact 1/r
  double xy[6] = {0, 0, 0, 0, 0, 2}, qq[2] = {1, 3}, pp[2], gg[6];
  ev->evaluate(2, xy, qq, 2, xy, pp, gg);
  EXPECT_NEAR(pp[0], 1.5, 1e-15);
  EXPECT_NEAR(pp[1], 0.5, 1e-15);
  EXPECT_NEAR(gg[2], 3.0 / 4.0, 1e-15);     // d/dz0 of 3/|z0 - 2| at z0 = 0
  EXPECT_NEAR(gg[5], -1.0 / 4.0, 1e-15);
}

struct Case {
  const char *name;
  Points pts;
  double max_pot, max_grad;
};

TEST(EngineAccuracy, DistributionsAtOrder6)
{
  const int n = 12000;
  Case cases[] = {
      {"uniform cube", uniform_cube(n, 1), 1e-5, 2e-5},
      {"plummer sphere", plummer(n, 2), 1e-5, 6e-5},
      {"two far clusters", two_clusters(n, 3), 1e-5, 2e-5},
      {"plane", plane(n, 4), 1e-5, 2e-5},
      {"neutral dipoles", dipoles(n / 2, 5), 1e-5, 2e-5},
  };
  for (auto &c : cases) {
    kifmm::Options o;
    o.order = 6;
    o.leaf_size = 64;
    auto ev = kifmm::make_evaluator(KernelSpec{}, o);
    Errors e = fmm_errors(*ev, c.pts);
    report(c.name, 6, e);
    EXPECT_LT(e.pot, c.max_pot) << c.name;
    EXPECT_LT(e.grad, c.max_grad) << c.name;
    EXPECT_GE(ev->stats().depth, 3) << c.name;    // far field really exercised
  }
}

TEST(EngineAccuracy, ErrorFallsMonotonicallyWithOrder)
{
  Points p = uniform_cube(20000, 21);
  const Reference ref = reference(KernelSpec{}, p, p);
  double prev = 1.0;
  for (int order = 3; order <= 14; ++order) {
    kifmm::Options o;
    o.order = order;
    o.leaf_size = 160;
    auto ev = kifmm::make_evaluator(KernelSpec{}, o);
    Errors e = fmm_errors(*ev, p, p, ref);
    report("uniform 2e4 leaf 160", order, e);
    EXPECT_LT(e.grad, prev) << "order " << order;
    EXPECT_LT(e.pot, 2 * prev) << "order " << order;
    prev = e.grad;
    if (order == 4) EXPECT_LT(e.grad, 5e-4);
    if (order == 6) EXPECT_LT(e.grad, 2e-5);
    if (order == 8) EXPECT_LT(e.grad, 5e-7);
    if (order == 12) EXPECT_LT(e.grad, 1e-9);
  }
  EXPECT_LT(prev, 1e-10);
}

TEST(EngineAccuracy, LargeUniform1e5SampledTargets)
{
  const std::size_t n = 100000, ns = 1000;
  Points p = uniform_cube(n, 31);
  kifmm::Options o;
  o.order = 5;
  auto ev = kifmm::make_evaluator(KernelSpec{}, o);
  std::vector<double> pot(n), g(3 * n);
  ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
  // direct sum on every 100th target
  Points t;
  std::vector<double> ps, gs;
  for (std::size_t i = 0; i < n; i += n / ns) {
    t.xyz.insert(t.xyz.end(), &p.xyz[3 * i], &p.xyz[3 * i + 3]);
    t.q.push_back(0);
    ps.push_back(pot[i]);
    gs.insert(gs.end(), &g[3 * i], &g[3 * i + 3]);
  }
  std::vector<double> pr(t.size()), gr(3 * t.size());
  kifmm::direct_sum(KernelSpec{}, n, p.xyz.data(), p.q.data(), t.size(), t.xyz.data(), pr.data(), gr.data());
  Errors e{rel_l2(ps, pr), rel_l2(gs, gr)};
  report("uniform 1e5 (sampled)", 5, e);
  EXPECT_LT(e.pot, 1e-4);
  EXPECT_LT(e.grad, 1e-4);
  EXPECT_GE(ev->stats().depth, 3);
}

TEST(EngineAccuracy, YukawaMatchesDirectSum)
{
  Points p = uniform_cube(12000, 41, 2.0);
  for (double kappa : {0.5, 4.0}) {
    KernelSpec k{KernelType::Yukawa, kappa};
    const Reference ref = reference(k, p, p);
    double prev = 1.0;
    for (int order : {4, 6, 8}) {
      kifmm::Options o;
      o.order = order;
      o.leaf_size = 64;
      auto ev = kifmm::make_evaluator(k, o);
      Errors e = fmm_errors(*ev, p, p, ref);
      std::printf("  yukawa kappa=%g", kappa);
      report("", order, e);
      EXPECT_LT(e.grad, prev);
      prev = e.grad;
    }
    EXPECT_LT(prev, 1e-6) << "kappa " << kappa;
  }
  // strong screening over many levels: still finite and accurate
  Points c = plummer(8000, 42);
  Errors e = fmm_errors(KernelSpec{KernelType::Yukawa, 20.0}, 6, 64, c);
  report("yukawa kappa=20 plummer", 6, e);
  EXPECT_LT(e.grad, 1e-4);
}
