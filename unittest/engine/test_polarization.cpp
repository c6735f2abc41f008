// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Induced point dipoles (kifmm::solve_induced_dipoles) against a dense direct solve of the same
// linear system: polarizable spheres (Clausius-Mossotti polarizabilities) in an external field
// and the field of fixed charges, Laplace and Yukawa; the field of the dipoles by the FMM and by
// the exact sum; the restart from a converged solution, and the indefinite system of point
// dipoles too close for their polarizabilities.
#include "kifmm.h"
#include "test_util.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace kifmm_test;

namespace {

// n spheres of radius a placed at random without overlap (gap >= 0.1 a) in a cube of edge L
std::vector<double> spheres(std::size_t n, double a, double L, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5 * L, 0.5 * L);
  std::vector<double> x;
  const double dmin2 = (2.1 * a) * (2.1 * a);
  while (x.size() < 3 * n) {
    const double c[3] = {u(rng), u(rng), u(rng)};
    bool ok = true;
    for (std::size_t j = 0; j < x.size() && ok; j += 3) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (c[d] - x[j + d]) * (c[d] - x[j + d]);
      ok = r2 >= dmin2;
    }
    if (ok) x.insert(x.end(), c, c + 3);
  }
  return x;
}

struct System {
  std::size_t n;
  std::vector<double> xyz, alpha, e0;
};

// polarizable spheres of radius 1 (alpha = a^3 (eps - 1) / (eps + 2), eps = 10; every fifth
// one not polarizable, alpha 0) in a uniform field plus the field of 40 fixed charges
System polarizable_spheres(const kifmm::KernelSpec &kernel, std::size_t n, unsigned seed)
{
  System s{n, spheres(n + 40, 1.0, 2.6 * std::cbrt((double) n + 40), seed), {}, {}};
  std::vector<double> cxyz(s.xyz.end() - 120, s.xyz.end()), cq(40);
  s.xyz.resize(3 * n);
  for (std::size_t k = 0; k < cq.size(); ++k) cq[k] = k % 2 ? 1.5 : -1.0;
  s.alpha.assign(n, 9.0 / 12.0);
  for (std::size_t i = 0; i < n; i += 5) s.alpha[i] = 0.0;
  std::vector<double> g(3 * n);
  kifmm::direct_sum(kernel, cq.size(), cxyz.data(), cq.data(), n, s.xyz.data(), nullptr, g.data());
  s.e0.resize(3 * n);
  const double ext[3] = {0.05, -0.02, 0.3};
  for (std::size_t k = 0; k < 3 * n; ++k) s.e0[k] = ext[k % 3] - g[k];
  return s;
}

// the field e = -grad phi of dipoles mu at the points, by the exact sum
void exact_field(const kifmm::KernelSpec &kernel, const System &s, const double *mu, double *e)
{
  std::vector<double> g(3 * s.n);
  kifmm::direct_sum_dipoles(kernel, s.n, s.xyz.data(), nullptr, mu, s.n, s.xyz.data(), nullptr, g.data(), nullptr);
  for (std::size_t k = 0; k < 3 * s.n; ++k) e[k] = -g[k];
}

// the dense solve: the matrix of the field of unit dipoles (column 3j + d: the field of a unit
// dipole at j along d, by the exact sum), A = diag(1 / alpha) - T over the polarizable points
std::vector<double> dense_solution(const kifmm::KernelSpec &kernel, const System &s)
{
  std::vector<std::size_t> pol;
  for (std::size_t i = 0; i < s.n; ++i)
    if (s.alpha[i] > 0) pol.push_back(i);
  const std::size_t m = 3 * pol.size();
  Eigen::MatrixXd A(m, m);
  Eigen::VectorXd b(m);
  std::vector<double> unit(3 * s.n, 0.0), e(3 * s.n);
  for (std::size_t c = 0; c < m; ++c) {
    const std::size_t j = pol[c / 3];
    unit[3 * j + c % 3] = 1.0;
    exact_field(kernel, s, unit.data(), e.data());
    unit[3 * j + c % 3] = 0.0;
    for (std::size_t r = 0; r < m; ++r) A(r, c) = -e[3 * pol[r / 3] + r % 3];
    A(c, c) += 1.0 / s.alpha[j];
    b(c) = s.e0[3 * j + c % 3];
  }
  EXPECT_LE((A - A.transpose()).norm(), 1e-12 * A.norm()) << "the operator is symmetric";
  const Eigen::VectorXd x = A.ldlt().solve(b);
  std::vector<double> mu(3 * s.n, 0.0);
  for (std::size_t c = 0; c < m; ++c) mu[3 * pol[c / 3] + c % 3] = x(c);
  return mu;
}

double identity(double x)
{
  return x;
}

kifmm::PolarizationSolve solve(const System &s, const std::function<void(const double *, double *)> &field,
                               double tol, std::vector<double> &mu)
{
  return kifmm::solve_induced_dipoles(s.n, s.alpha.data(), s.e0.data(), field, identity, tol, 200, mu.data());
}

class Polarization : public ::testing::TestWithParam<kifmm::KernelType> {
 protected:
  kifmm::KernelSpec kernel() const
  {
    kifmm::KernelSpec k;
    k.type = GetParam();
    if (k.type == kifmm::KernelType::Yukawa) k.kappa = 0.3;
    return k;
  }
};

// with the exact field the solver reaches the dense solution; with the FMM field at order 10
// (and a tree deep enough to have a far field) the dipoles differ from it at the FMM's accuracy
TEST_P(Polarization, EqualsTheDenseSolve)
{
  const kifmm::KernelSpec k = kernel();
  const System s = polarizable_spheres(k, 600, 17);
  const std::vector<double> ref = dense_solution(k, s);

  std::vector<double> mu(3 * s.n, 0.0);
  const kifmm::PolarizationSolve exact =
      solve(s, [&](const double *m, double *e) { exact_field(k, s, m, e); }, 1e-12, mu);
  EXPECT_TRUE(exact.converged);
  EXPECT_LE(exact.residual, 1e-12);
  EXPECT_EQ(exact.evaluations, exact.iterations);    // zero start: no evaluation of it
  EXPECT_LE(rel_l2(mu, ref), 1e-10);
  for (std::size_t i = 0; i < s.n; i += 5) EXPECT_EQ(mu[3 * i] * mu[3 * i] + mu[3 * i + 1] * mu[3 * i + 1], 0.0);
  std::printf("  exact field: %d iterations, dipoles %.2e from the dense solve\n", exact.iterations, rel_l2(mu, ref));

  kifmm::Options o;
  o.order = 10;
  o.leaf_size = 32;
  auto ev = kifmm::make_evaluator(k, o);
  std::vector<double> g(3 * s.n);
  auto fmm_field = [&](const double *m, double *e) {
    ev->evaluate_dipoles(s.n, s.xyz.data(), nullptr, m, s.n, s.xyz.data(), nullptr, g.data(), nullptr);
    for (std::size_t q = 0; q < 3 * s.n; ++q) e[q] = -g[q];
  };
  std::fill(mu.begin(), mu.end(), 0.0);
  const kifmm::PolarizationSolve fmm = solve(s, fmm_field, 1e-10, mu);
  EXPECT_TRUE(fmm.converged);
  EXPECT_GT(ev->stats().depth, 1);
  std::printf("  fmm field, order 10: %d iterations, dipoles %.2e from the dense solve\n", fmm.iterations,
              rel_l2(mu, ref));
  EXPECT_LE(rel_l2(mu, ref), 1e-6);    // the field error of order 10 (1e-8 .. 1e-7) through the system

  // started from its own solution: one evaluation, no iteration
  const kifmm::PolarizationSolve again = solve(s, fmm_field, 1e-8, mu);
  EXPECT_TRUE(again.converged);
  EXPECT_EQ(again.iterations, 0);
  EXPECT_EQ(again.evaluations, 1);
}

// the tolerance is what the returned dipoles meet: the true residual of the exact operator
TEST_P(Polarization, ResidualIsTheReturnedDipoles)
{
  const kifmm::KernelSpec k = kernel();
  const System s = polarizable_spheres(k, 300, 5);
  for (double tol : {1e-3, 1e-6}) {
    std::vector<double> mu(3 * s.n, 0.0), e(3 * s.n);
    const kifmm::PolarizationSolve r =
        solve(s, [&](const double *m, double *f) { exact_field(k, s, m, f); }, tol, mu);
    ASSERT_TRUE(r.converged);
    exact_field(k, s, mu.data(), e.data());
    double num = 0, den = 0;
    for (std::size_t i = 0; i < s.n; ++i)
      for (int d = 0; d < 3; ++d) {
        if (!(s.alpha[i] > 0)) continue;
        const double res = s.e0[3 * i + d] - (mu[3 * i + d] / s.alpha[i] - e[3 * i + d]);
        num += s.alpha[i] * res * res;
        den += s.alpha[i] * s.e0[3 * i + d] * s.e0[3 * i + d];
      }
    EXPECT_LE(std::sqrt(num / den), tol);
    EXPECT_NEAR(std::sqrt(num / den), r.residual, 1e-9 + 1e-6 * r.residual);
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, Polarization,
                         ::testing::Values(kifmm::KernelType::Laplace, kifmm::KernelType::Yukawa),
                         [](const auto &info) {
                           return info.param == kifmm::KernelType::Laplace ? "Laplace" : "Yukawa";
                         });

// two point dipoles closer than their polarizabilities allow (alpha 1 at distance 1: along the
// axis 1 / alpha - 2 / r^3 < 0): no minimum, said so instead of a diverging answer
TEST(PolarizationLimits, TooClosePointsAreIndefinite)
{
  const kifmm::KernelSpec k;
  System s{2, {0, 0, 0, 1, 0, 0}, {1.0, 1.0}, {1, 0, 0, 1, 0, 0}};
  std::vector<double> mu(6, 0.0);
  const kifmm::PolarizationSolve r =
      solve(s, [&](const double *m, double *e) { exact_field(k, s, m, e); }, 1e-10, mu);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.indefinite);
  // apart at distance 2 the same pair converges: mu = alpha e0 / (1 - 2 alpha / r^3) along the axis
  s.xyz[3] = 2.0;
  std::fill(mu.begin(), mu.end(), 0.0);
  const kifmm::PolarizationSolve ok =
      solve(s, [&](const double *m, double *e) { exact_field(k, s, m, e); }, 1e-12, mu);
  EXPECT_TRUE(ok.converged);
  EXPECT_NEAR(mu[0], 1.0 / (1.0 - 2.0 / 8.0), 1e-12);
  EXPECT_NEAR(mu[3], mu[0], 1e-12);
}

// no field at the polarizable points: no dipoles, whatever the start
TEST(PolarizationLimits, NoFieldGivesNoDipoles)
{
  const kifmm::KernelSpec k;
  System s{2, {0, 0, 0, 3, 0, 0}, {1.0, 1.0}, {0, 0, 0, 0, 0, 0}};
  std::vector<double> mu = {1, 2, 3, 4, 5, 6};
  const kifmm::PolarizationSolve r =
      solve(s, [&](const double *m, double *e) { exact_field(k, s, m, e); }, 1e-10, mu);
  EXPECT_TRUE(r.converged);
  for (double v : mu) EXPECT_EQ(v, 0.0);
}

}    // namespace
