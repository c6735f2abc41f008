// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The engine's diagnostics (kifmm.h, diagnostics.cpp): per-point virial against the pairwise
// sum, exact reference gradients, sampling without replacement and the sampled error
// estimate, memory estimate.
#include "communicator.h"
#include "kifmm.h"
#include "periodic.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <utility>

using namespace kifmm;

namespace {
// 1/2 sum_j (x_i - x_j)_a F_ij,b with F_ij = prefactor q_i q_j grad_x G(x_i, x_j) (Laplace)
std::vector<double> pairwise_virial(const kifmm_test::Points &p, double prefactor)
{
  const std::size_t n = p.size();
  std::vector<double> w(6 * n, 0.0);
  const int ia[6] = {0, 1, 2, 0, 0, 1}, ib[6] = {0, 1, 2, 1, 2, 2};
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      double r[3], r2 = 0;
      for (int d = 0; d < 3; ++d) {
        r[d] = p.xyz[3 * i + d] - p.xyz[3 * j + d];
        r2 += r[d] * r[d];
      }
      const double g = -1.0 / (r2 * std::sqrt(r2));    // d/dx_i 1/|x_i - x_j| = -r / r^3
      for (int c = 0; c < 6; ++c)
        w[6 * i + c] += 0.5 * r[ia[c]] * prefactor * p.q[i] * p.q[j] * g * r[ib[c]];
    }
  return w;
}
}    // namespace

TEST(Diagnostics, PointVirialEqualsPairwiseSum)
{
  const auto p = kifmm_test::uniform_cube(600, 11);
  Options opt;
  opt.order = 8;
  opt.leaf_size = 40;
  auto ev = make_evaluator(KernelSpec{}, opt);
  std::vector<double> grad(3 * p.size(), 0.0);
  ev->evaluate(p.size(), p.xyz.data(), p.q.data(), p.size(), p.xyz.data(), nullptr, grad.data());
  std::vector<double> w(6 * p.size());
  double c[3];
  const double prefactor = -2.5;
  point_virial(*ev, nullptr, p.size(), p.xyz.data(), p.q.data(), grad.data(), prefactor, w.data(), c);
  const auto ref = pairwise_virial(p, prefactor);
  double num = 0, den = 0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    num += (w[k] - ref[k]) * (w[k] - ref[k]);
    den += ref[k] * ref[k];
  }
  EXPECT_LT(std::sqrt(num / den), 1e-5);
  for (int d = 0; d < 3; ++d) EXPECT_LT(std::fabs(c[d]), 1.0);    // centre of the box
  // with a serial communicator: the same
  SerialCommunicator serial;
  std::vector<double> w1(w.size());
  point_virial(*ev, &serial, p.size(), p.xyz.data(), p.q.data(), grad.data(), prefactor, w1.data(), c);
  EXPECT_EQ(w, w1);
}

TEST(Diagnostics, ExactGradientIsTheDirectSumOrTheEwaldSum)
{
  const auto p = kifmm_test::uniform_cube(300, 5);
  Options opt;
  auto ev = make_evaluator(KernelSpec{}, opt);
  std::vector<double> g(30, 0.0), ref(30, 0.0);
  exact_gradient(*ev, nullptr, p.size(), p.xyz.data(), p.q.data(), 10, p.xyz.data(), g.data());
  direct_sum(KernelSpec{}, p.size(), p.xyz.data(), p.q.data(), 10, p.xyz.data(), nullptr, ref.data());
  EXPECT_EQ(g, ref);
  // periodic cell: not the open sum
  opt.periodic = opt.fixed_root = true;
  opt.root_half_width = 1.0;
  auto evp = make_evaluator(KernelSpec{}, opt);
  std::vector<double> gp(30, 0.0);
  exact_gradient(*evp, nullptr, p.size(), p.xyz.data(), p.q.data(), 10, p.xyz.data(), gp.data());
  double diff = 0;
  for (int k = 0; k < 30; ++k) diff = std::max(diff, std::fabs(gp[k] - ref[k]));
  EXPECT_GT(diff, 1e-3);
  std::vector<double> ewald(30, 0.0);
  periodic_direct_sum(KernelSpec{}, opt.root_center, 1.0, p.size(), p.xyz.data(), p.q.data(), 10, p.xyz.data(),
                      nullptr, ewald.data());
  EXPECT_EQ(reference_order(evp->options(), p.size(), 10), 0);
  EXPECT_EQ(gp, ewald);
}

// Above 5e6 source-target pairs in a periodic box the reference is the engine at order 14
// (for orders up to 11): the Ewald sum to 1e-10 relative, coulomb in a cube and yukawa in a
// rectangular cell, targets at sources (coincident) and elsewhere.
TEST(Diagnostics, ExactGradientInALargePeriodicBoxIsTheEngineAtOrder14)
{
  const std::size_t nt = 1000, nref = 60;
  const std::array<double, 3> cube{1.0, 1.0, 1.0}, box{1.0, 0.75, 0.5};
  for (const auto &[shape, kernel] :
       {std::pair{cube, KernelSpec{}}, std::pair{box, KernelSpec{KernelType::Yukawa, 2.0}}}) {
    auto p = kifmm_test::neutral(kifmm_test::uniform_cube(6000, 8));
    for (std::size_t k = 0; k < p.size(); ++k)
      for (int d = 0; d < 3; ++d) p.xyz[3 * k + d] *= shape[d];
    std::vector<double> t(p.xyz.begin(), p.xyz.begin() + 3 * nt);
    for (std::size_t k = 0; k < nt; k += 2) t[3 * k] *= 0.9;    // half of them between the points
    Options opt;
    opt.order = 7;
    opt.periodic = opt.fixed_root = true;
    for (int d = 0; d < 3; ++d) opt.root_shape[d] = shape[d];
    auto ev = make_evaluator(kernel, opt);
    EXPECT_EQ(reference_order(ev->options(), p.size(), nt), 14);
    Options high = opt;
    high.order = 12;
    EXPECT_EQ(reference_order(high, p.size(), nt), 0);
    EXPECT_EQ(reference_order(opt, p.size(), 500), 0);
    std::vector<double> g(3 * nt, 0.0), ewald(3 * nref, 0.0);
    exact_gradient(*ev, nullptr, p.size(), p.xyz.data(), p.q.data(), nt, t.data(), g.data());
    periodic_direct_sum(kernel, opt.root_center, 1.0, p.size(), p.xyz.data(), p.q.data(), nref, t.data(), nullptr,
                        ewald.data(), shape.data());
    double num = 0, den = 0;
    for (std::size_t k = 0; k < 3 * nref; ++k) {
      num += (g[k] - ewald[k]) * (g[k] - ewald[k]);
      den += ewald[k] * ewald[k];
    }
    EXPECT_LT(std::sqrt(num / den), 1e-10) << "kernel " << (int) kernel.type << ", shape " << shape[2];
    EXPECT_GT(num, 0.0);    // not the Ewald sum itself
  }
}

// The same for charges and dipoles (p p p coulomb): gradients and second derivatives
TEST(Diagnostics, ExactDipoleFieldInALargePeriodicBoxIsTheEngineAtOrder14)
{
  const std::size_t nt = 1000, nref = 60;
  const auto p = kifmm_test::neutral(kifmm_test::uniform_cube(6000, 9));
  std::vector<double> mu(3 * p.size());
  for (std::size_t k = 0; k < mu.size(); ++k) mu[k] = 0.01 * std::sin(1.0 + 7.0 * k);
  const std::vector<double> t(p.xyz.begin(), p.xyz.begin() + 3 * nt);
  Options opt;
  opt.order = 8;
  opt.periodic = opt.fixed_root = true;
  auto ev = make_evaluator(KernelSpec{}, opt);
  ASSERT_EQ(reference_order(ev->options(), p.size(), nt), 14);
  std::vector<double> g(3 * nt, 0.0), h(6 * nt, 0.0), rg(3 * nref), rh(6 * nref);
  exact_dipole_field(*ev, nullptr, p.size(), p.xyz.data(), p.q.data(), mu.data(), nt, t.data(), g.data(), h.data());
  periodic_dipole_direct_sum(opt.root_center, 1.0, nullptr, p.size(), p.xyz.data(), p.q.data(), mu.data(), nref,
                             t.data(), nullptr, rg.data(), rh.data());
  auto rel = [](const std::vector<double> &a, const std::vector<double> &ref) {
    double num = 0, den = 0;
    for (std::size_t k = 0; k < ref.size(); ++k) {
      num += (a[k] - ref[k]) * (a[k] - ref[k]);
      den += ref[k] * ref[k];
    }
    return std::sqrt(num / den);
  };
  EXPECT_LT(rel(g, rg), 1e-10);
  EXPECT_LT(rel(h, rh), 1e-10);
  EXPECT_GT(rel(g, rg), 0.0);    // not the Ewald sum itself
}

TEST(Diagnostics, SampleWithoutReplacement)
{
  std::vector<std::size_t> c(100);
  for (std::size_t k = 0; k < c.size(); ++k) c[k] = 1000 + k;
  const auto s = sample_without_replacement(c, 30, 99);
  ASSERT_EQ(s.size(), 30u);
  std::set<std::size_t> distinct(s.begin(), s.end());
  EXPECT_EQ(distinct.size(), 30u);
  for (std::size_t v : s) EXPECT_TRUE(v >= 1000 && v < 1100);
  EXPECT_EQ(sample_without_replacement(c, 30, 99), s);    // deterministic for a seed
  EXPECT_NE(sample_without_replacement(c, 30, 98), s);
  EXPECT_EQ(sample_without_replacement(c, 200, 1), c);
}

TEST(Diagnostics, SampledRelativeError)
{
  EXPECT_DOUBLE_EQ(sampled_relative_error(4.0, 16.0, 10, 10, 999.0), 0.5);    // all sampled
  // a tenth sampled: its squared error times 10 over all points' squared values
  EXPECT_DOUBLE_EQ(sampled_relative_error(1.0, 5.0, 10, 100, 1000.0), 0.1);
  EXPECT_EQ(sampled_relative_error(1.0, 1.0, 0, 100, 1.0), -1.0);
  EXPECT_EQ(relative_rms(0.0, 0.0), 0.0);
  EXPECT_TRUE(std::isinf(relative_rms(1.0, 0.0)));
}

TEST(Diagnostics, MemoryEstimateGrowsWithPointsOrderAndGrid)
{
  Options opt;
  opt.order = 6;
  opt.leaf_size = 64;
  const double a = estimate_memory_bytes(opt, 100000, 0);
  EXPECT_GT(a, 30.0 * 8 * 100000);    // at least the per-point arrays
  EXPECT_GT(estimate_memory_bytes(opt, 1000000, 0), 9 * a);
  EXPECT_DOUBLE_EQ(estimate_memory_bytes(opt, 100000, 12345) - a, 12345.0);
  Options high = opt;
  high.order = 10;
  EXPECT_GT(estimate_memory_bytes(high, 100000, 0), a);
  Options grid = opt;
  grid.periodic_grid = 8;
  EXPECT_GT(estimate_memory_bytes(grid, 100000, 0), a);
}
