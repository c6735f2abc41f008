// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point dipoles (Evaluator::evaluate_dipoles, open boundaries): the exact sum against finite
// differences (dipole = limit of a charge pair; gradient and second derivatives = derivatives
// of the potential and gradient in the target position), then the FMM against the exact sum
// on uniform and clustered points, Laplace and Yukawa, charges and dipoles mixed or dipoles
// alone, with coincident points; periodic boundaries are refused.
#include "fmm_core.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

using namespace kifmm_test;

namespace {

struct Dipoles {
  Points p;                 // positions and charges
  std::vector<double> mu;   // 3 per point
};

Dipoles random_dipoles(Points p, unsigned seed, bool charges)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Dipoles d{std::move(p), {}};
  d.mu.resize(3 * d.p.size());
  for (auto &m : d.mu) m = u(rng);
  if (!charges) std::fill(d.p.q.begin(), d.p.q.end(), 0.0);
  return d;
}

struct Field {
  std::vector<double> pot, grad, hess;
};

Field exact(const kifmm::KernelSpec &k, const Dipoles &s, const Points &t)
{
  Field f{std::vector<double>(t.size()), std::vector<double>(3 * t.size()), std::vector<double>(6 * t.size())};
  kifmm::direct_sum_dipoles(k, s.p.size(), s.p.xyz.data(), s.p.q.data(), s.mu.data(), t.size(), t.xyz.data(),
                            f.pot.data(), f.grad.data(), f.hess.data());
  return f;
}

Field fmm(kifmm::Evaluator &ev, const Dipoles &s, const Points *t = nullptr)
{
  const Points &tt = t ? *t : s.p;
  Field f{std::vector<double>(tt.size()), std::vector<double>(3 * tt.size()), std::vector<double>(6 * tt.size())};
  ev.evaluate_dipoles(s.p.size(), s.p.xyz.data(), s.p.q.data(), s.mu.data(), tt.size(),
                      t ? tt.xyz.data() : s.p.xyz.data(), f.pot.data(), f.grad.data(), f.hess.data());
  return f;
}

kifmm::KernelSpec yukawa(double kappa)
{
  kifmm::KernelSpec k;
  k.type = kifmm::KernelType::Yukawa;
  k.kappa = kappa;
  return k;
}

// a dipole m at y is the limit of charges +1/e at y + e m/2 and -1/e at y - e m/2
TEST(Dipoles, ExactSumIsTheLimitOfAChargePair)
{
  for (const auto &k : {kifmm::KernelSpec{}, yukawa(2.5)}) {
    const Dipoles s = random_dipoles(uniform_cube(12, 3), 4, false);
    const Points t = uniform_cube(7, 5, 2.0);
    const Field f = exact(k, s, t);
    const double e = 1e-5;
    Points pair;
    for (std::size_t j = 0; j < s.p.size(); ++j)
      for (int sg : {1, -1}) {
        for (int d = 0; d < 3; ++d) pair.xyz.push_back(s.p.xyz[3 * j + d] + sg * 0.5 * e * s.mu[3 * j + d]);
        pair.q.push_back(sg / e);
      }
    std::vector<double> pot(t.size());
    kifmm::direct_sum(k, pair.size(), pair.xyz.data(), pair.q.data(), t.size(), t.xyz.data(), pot.data(), nullptr);
    EXPECT_LT(rel_l2(pot, f.pot), 1e-8);
  }
}

// gradient and second derivatives: central differences of the potential and the gradient
TEST(Dipoles, ExactGradientAndSecondDerivativesAreDerivatives)
{
  for (const auto &k : {kifmm::KernelSpec{}, yukawa(1.5)}) {
    const Dipoles s = random_dipoles(uniform_cube(15, 7), 8, true);
    const Points t = uniform_cube(6, 9, 1.5);
    const Field f = exact(k, s, t);
    const double h = 1e-5;
    std::vector<double> fd_grad(3 * t.size()), fd_hess(6 * t.size());
    const int hc[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
    for (int b = 0; b < 3; ++b) {
      Points tp = t, tm = t;
      for (std::size_t i = 0; i < t.size(); ++i) tp.xyz[3 * i + b] += h, tm.xyz[3 * i + b] -= h;
      const Field fp = exact(k, s, tp), fm = exact(k, s, tm);
      for (std::size_t i = 0; i < t.size(); ++i) {
        fd_grad[3 * i + b] = (fp.pot[i] - fm.pot[i]) / (2 * h);
        for (int a = 0; a <= b; ++a) fd_hess[6 * i + hc[a][b]] = (fp.grad[3 * i + a] - fm.grad[3 * i + a]) / (2 * h);
      }
    }
    EXPECT_LT(rel_l2(fd_grad, f.grad), 1e-7);
    EXPECT_LT(rel_l2(fd_hess, f.hess), 1e-7);
  }
}

struct Case {
  const char *name;
  Points pts;
  bool charges;
  kifmm::KernelSpec kernel;
};

// FMM against the exact sum (sources = targets): every output converges with the order
TEST(Dipoles, FmmEqualsTheExactSum)
{
  const std::vector<Case> cases = {{"uniform, charges and dipoles", uniform_cube(3000, 11), true, {}},
                                   {"two clusters, dipoles only", two_clusters(3000, 12), false, {}},
                                   {"plummer, yukawa", plummer(2000, 13), true, yukawa(3.0)}};
  for (const auto &c : cases) {
    const Dipoles s = random_dipoles(c.pts, 21, c.charges);
    const Field ref = exact(c.kernel, s, s.p);
    double last[3] = {1, 1, 1};
    for (int order : {4, 6, 8, 10}) {
      kifmm::Options o;
      o.order = order;
      o.leaf_size = 64;
      auto ev = kifmm::make_evaluator(c.kernel, o);
      const Field f = fmm(*ev, s);
      const double err[3] = {rel_l2(f.pot, ref.pot), rel_l2(f.grad, ref.grad), rel_l2(f.hess, ref.hess)};
      std::printf("%-30s p=%2d  pot %.2e  grad %.2e  hess %.2e\n", c.name, order, err[0], err[1], err[2]);
      for (int m = 0; m < 3; ++m) {
        EXPECT_LT(err[m], last[m]) << c.name << " order " << order << " output " << m;
        last[m] = err[m];
      }
      EXPECT_EQ(ev->stats().coincident_pairs, 0u);
    }
    EXPECT_LT(last[0], 1e-7) << c.name;
    EXPECT_LT(last[1], 1e-7) << c.name;
    EXPECT_LT(last[2], 1e-6) << c.name;
  }
}

// separate targets, no second derivatives, sources with zero charge and zero dipole skipped
TEST(Dipoles, SeparateTargetsWithoutSecondDerivatives)
{
  Dipoles s = random_dipoles(uniform_cube(2500, 31), 32, true);
  for (std::size_t j = 0; j < s.p.size(); j += 5) s.p.q[j] = 0, s.mu[3 * j] = s.mu[3 * j + 1] = s.mu[3 * j + 2] = 0;
  const Points t = uniform_cube(800, 33, 1.3);
  const Field ref = exact({}, s, t);
  kifmm::Options o;
  o.order = 8;
  auto ev = kifmm::make_evaluator({}, o);
  std::vector<double> pot(t.size()), grad(3 * t.size());
  ev->evaluate_dipoles(s.p.size(), s.p.xyz.data(), s.p.q.data(), s.mu.data(), t.size(), t.xyz.data(), pot.data(),
                       grad.data(), nullptr);
  EXPECT_LT(rel_l2(pot, ref.pot), 1e-6);
  EXPECT_LT(rel_l2(grad, ref.grad), 1e-6);
  EXPECT_EQ(ev->stats().n_sources, s.p.size() - s.p.size() / 5);
  // and a plain charge evaluation afterwards is unchanged by the dipole call
  std::vector<double> p1(t.size()), p2(t.size());
  ev->evaluate(s.p.size(), s.p.xyz.data(), s.p.q.data(), t.size(), t.xyz.data(), p1.data(), nullptr);
  kifmm::direct_sum({}, s.p.size(), s.p.xyz.data(), s.p.q.data(), t.size(), t.xyz.data(), p2.data(), nullptr);
  EXPECT_LT(rel_l2(p1, p2), 1e-6);
}

// coincident points: no contribution, counted, finite results
TEST(Dipoles, CoincidentPointsAreExcludedAndCounted)
{
  Dipoles s = random_dipoles(uniform_cube(1500, 41), 42, true);
  for (int d = 0; d < 3; ++d) s.p.xyz[3 * 7 + d] = s.p.xyz[3 * 8 + d];
  const Field ref = exact({}, s, s.p);
  kifmm::Options o;
  o.order = 8;
  auto ev = kifmm::make_evaluator({}, o);
  const Field f = fmm(*ev, s);
  for (double v : f.hess) ASSERT_TRUE(std::isfinite(v));
  EXPECT_EQ(ev->stats().coincident_pairs, 2u);
  EXPECT_LT(rel_l2(f.grad, ref.grad), 1e-6);
  EXPECT_LT(rel_l2(f.hess, ref.hess), 1e-5);
}

TEST(Dipoles, PeriodicBoundariesAreRefused)
{
  const Dipoles s = random_dipoles(uniform_cube(100, 51), 52, true);
  auto ev = kifmm::make_evaluator({}, periodic_options(6, 32));
  EXPECT_THROW(fmm(*ev, s), std::invalid_argument);
}

}    // namespace
