// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Kernel pair functions and the direct sum against plain scalar references.
#include "direct_sum.h"
#include "kernels.h"
#include "p2p.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace kifmm_test;

TEST(EngineKernels, VectorizableExpMatchesStdExp)
{
  std::mt19937_64 g(3);
  std::uniform_real_distribution<double> u(-708.0, 5.0), s(-3.0, 0.0);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const double x = (i % 2) ? u(g) : s(g);
    const double a = kifmm::exp_accurate(x), b = std::exp(x);
    worst = std::max(worst, std::fabs(a - b) / b);
  }
  EXPECT_LT(worst, 5e-16);
  EXPECT_EQ(kifmm::exp_accurate(0.0), 1.0);
  EXPECT_EQ(kifmm::exp_accurate(-1000.0), 0.0);
}

TEST(EngineKernels, DirectSumMatchesScalarReference)
{
  Points s = uniform_cube(301, 1), t = uniform_cube(77, 2);
  std::copy(&s.xyz[0], &s.xyz[3], &t.xyz[0]);    // one coincident pair
  for (double kappa : {0.0, 1.7}) {
    kifmm::KernelSpec k{kappa > 0 ? kifmm::KernelType::Yukawa : kifmm::KernelType::Laplace, kappa};
    std::vector<double> p(t.size()), g(3 * t.size());
    kifmm::direct_sum(k, s.size(), s.xyz.data(), s.q.data(), t.size(), t.xyz.data(), p.data(), g.data());
    for (std::size_t i = 0; i < t.size(); ++i) {
      long double pr = 0, gr[3] = {0, 0, 0};
      for (std::size_t j = 0; j < s.size(); ++j) {
        long double d[3], r2 = 0;
        for (int c = 0; c < 3; ++c) {
          d[c] = (long double) t.xyz[3 * i + c] - s.xyz[3 * j + c];
          r2 += d[c] * d[c];
        }
        if (r2 == 0) continue;
        const long double r = std::sqrt(r2), G = std::exp(-kappa * r) / r;
        const long double F = -G * (1 + kappa * r) / r2;
        pr += s.q[j] * G;
        for (int c = 0; c < 3; ++c) gr[c] += s.q[j] * F * d[c];
      }
      EXPECT_NEAR(p[i], (double) pr, 1e-13 * std::fabs((double) pr) + 1e-13);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(g[3 * i + c], (double) gr[c], 1e-12 * std::fabs((double) gr[c]) + 1e-12);
    }
    EXPECT_TRUE(std::isfinite(p[0]));
  }
}

TEST(EngineKernels, P2PPairAccuracyOverManyScales)
{
  // one source at a time, distances from 1e-30 to 1e30: 1/r and its gradient to ~1 ulp
  std::mt19937_64 g(5);
  std::uniform_real_distribution<double> u(-30, 30), v(-1, 1);
  double worst = 0, worst_g = 0;
  for (int k = 0; k < 50000; ++k) {
    const double sc = std::pow(10.0, u(g));
    double sx[11], sy[11], sz[11], sq[11];    // 11: full vector + masked tail
    for (int j = 0; j < 11; ++j) {
      sx[j] = v(g) * sc;
      sy[j] = v(g) * sc;
      sz[j] = v(g) * sc;
      sq[j] = (j == k % 11) ? 1.0 : 0.0;
    }
    double tx = 0, ty = 0, tz = 0, p = 0, gx = 0, gy = 0, gz = 0;
    kifmm::p2p<kifmm::LaplaceKernel, true, true, false>(kifmm::LaplaceKernel{}, {1, &tx, &ty, &tz}, {11, sx, sy, sz, sq},
                                                        {&p, &gx, &gy, &gz});
    const int j = k % 11;
    const long double r = std::sqrt((long double) sx[j] * sx[j] + (long double) sy[j] * sy[j] + (long double) sz[j] * sz[j]);
    worst = std::max(worst, (double) std::fabs((p - 1 / r) * r));
    const long double gref = sx[j] / (r * r * r);
    worst_g = std::max(worst_g, (double) std::fabs((gx - gref) / gref));
  }
  EXPECT_LT(worst, 4e-16);
  EXPECT_LT(worst_g, 2e-15);
}

// group_pair_sum (pairs inside a rigid body): potential and gradient equal direct_sum on the
// same points (coincident pair excluded), and the pair virial T_i,ab = sum_j q_j (x_i - x_j)_a
// dG/dx_i,b equals x_i,a g_i,b - (gradient of the potential of the strengths q_j x_j,a).
TEST(EngineKernels, GroupPairSumEqualsDirectSumAndMomentVirial)
{
  std::mt19937_64 g(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::size_t n = 9;
  std::vector<double> x(3 * n), q(n);
  for (auto &v : x) v = u(g);
  for (auto &v : q) v = u(g);
  for (int d = 0; d < 3; ++d) x[3 * 4 + d] = x[3 * 2 + d];    // a coincident pair: excluded
  q[6] = 0.0;
  for (const kifmm::KernelSpec k : {kifmm::KernelSpec{}, kifmm::KernelSpec{kifmm::KernelType::Yukawa, 1.7}}) {
    std::vector<double> p(n), gr(3 * n), t(6 * n), pd(n), gd(3 * n);
    kifmm::group_pair_sum(k, n, x.data(), q.data(), p.data(), gr.data(), t.data());
    kifmm::direct_sum(k, n, x.data(), q.data(), n, x.data(), pd.data(), gd.data());
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_NEAR(p[i], pd[i], 1e-12 * (1 + std::fabs(pd[i])));
      for (int d = 0; d < 3; ++d) EXPECT_NEAR(gr[3 * i + d], gd[3 * i + d], 1e-12 * (1 + std::fabs(gd[3 * i + d])));
    }
    const int comp[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    for (int a = 0; a < 3; ++a) {
      std::vector<double> qm(n), gm(3 * n);
      for (std::size_t j = 0; j < n; ++j) qm[j] = q[j] * x[3 * j + a];
      kifmm::direct_sum(k, n, x.data(), qm.data(), n, x.data(), nullptr, gm.data());
      for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 6; ++c) {
          if (comp[c][0] != a) continue;
          const int b = comp[c][1];
          const double want = x[3 * i + a] * gd[3 * i + b] - gm[3 * i + b];
          EXPECT_NEAR(t[6 * i + c], want, 1e-11 * (1 + std::fabs(want))) << "i " << i << " c " << c;
        }
    }
    // symmetric: T_xy computed as (x)(dG/dy) equals (y)(dG/dx)
    std::vector<double> qy(n), gy(3 * n);
    for (std::size_t j = 0; j < n; ++j) qy[j] = q[j] * x[3 * j + 1];
    kifmm::direct_sum(k, n, x.data(), qy.data(), n, x.data(), nullptr, gy.data());
    for (std::size_t i = 0; i < n; ++i) {
      const double yx = x[3 * i + 1] * gd[3 * i] - gy[3 * i];
      EXPECT_NEAR(t[6 * i + 3], yx, 1e-11 * (1 + std::fabs(yx)));
    }
  }
}
