// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point dipoles (Evaluator::evaluate_dipoles, open boundaries): the exact sum against finite
// differences (dipole = limit of a charge pair; gradient and second derivatives = derivatives
// of the potential and gradient in the target position), then the FMM against the exact sum
// on uniform and clustered points, Laplace and Yukawa, charges and dipoles mixed or dipoles
// alone, with coincident points; periodic boxes (octree, grid) against an Ewald sum of dipoles.
#include "fmm_core.h"
#include "periodic.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

using namespace kifmm_test;

namespace {

constexpr double kPi = 3.14159265358979323846;

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

// up to m of the candidates that lie farther than dmin from every source
Points targets_away_from(const Dipoles &s, const Points &cand, std::size_t m, double dmin)
{
  Points t;
  for (std::size_t i = 0; i < cand.size() && t.size() < m; ++i) {
    double r2min = 1e300;
    for (std::size_t j = 0; j < s.p.size(); ++j) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += std::pow(cand.xyz[3 * i + d] - s.p.xyz[3 * j + d], 2);
      r2min = std::min(r2min, r2);
    }
    if (r2min > dmin * dmin) {
      t.xyz.insert(t.xyz.end(), cand.xyz.begin() + 3 * i, cand.xyz.begin() + 3 * i + 3);
      t.q.push_back(0.0);
    }
  }
  return t;
}

// every source's charge, and its dipole as charges +-1/e at +-e mu/2
Points charge_pairs(const Dipoles &s, double e)
{
  Points pair;
  for (std::size_t j = 0; j < s.p.size(); ++j) {
    for (int d = 0; d < 3; ++d) pair.xyz.push_back(s.p.xyz[3 * j + d]);
    pair.q.push_back(s.p.q[j]);
    for (int sg : {1, -1}) {
      for (int d = 0; d < 3; ++d) pair.xyz.push_back(s.p.xyz[3 * j + d] + sg * 0.5 * e * s.mu[3 * j + d]);
      pair.q.push_back(sg / e);
    }
  }
  return pair;
}

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

// FMM against the exact sum (sources = targets, mutual near field): every output converges with
// the order
TEST(Dipoles, FmmEqualsTheExactSum)
{
  const std::vector<Case> cases = {{"uniform, charges and dipoles", uniform_cube(1000, 11), true, {}},
                                   {"two clusters, dipoles only", two_clusters(1000, 12), false, {}},
                                   {"plummer, yukawa", plummer(800, 13), true, yukawa(3.0)}};
  for (const auto &c : cases) {
    const Dipoles s = random_dipoles(c.pts, 21, c.charges);
    const Field ref = exact(c.kernel, s, s.p);
    double last[3] = {1, 1, 1};
    for (int order : {4, 7, 10}) {
      kifmm::Options o;
      o.order = order;
      o.leaf_size = 24;
      auto ev = kifmm::make_evaluator(c.kernel, o);
      const Field f = fmm(*ev, s);
      const double err[3] = {rel_l2(f.pot, ref.pot), rel_l2(f.grad, ref.grad), rel_l2(f.hess, ref.hess)};
      std::printf("%-30s p=%2d  pot %.2e  grad %.2e  hess %.2e\n", c.name, order, err[0], err[1], err[2]);
      for (int m = 0; m < 3; ++m) {
        EXPECT_LT(err[m], last[m]) << c.name << " order " << order << " output " << m;
        last[m] = err[m];
      }
      EXPECT_EQ(ev->stats().coincident_pairs, 0u);
      EXPECT_GT(ev->stats().mutual_pairs, 0u);    // sources = targets: the mutual near field
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

// erfc(alpha r)/r with its derivatives (kernels.h convention): the real-space part of Ewald
struct ErfcKernel {
  double alpha;
  void derivs3(double r2, double invr, double &G, double &F, double &H, double &T) const
  {
    const double r = r2 * invr, i2 = invr * invr, c = 2.0 * alpha / std::sqrt(kPi) * std::exp(-alpha * alpha * r2);
    const double a2 = 2.0 * alpha * alpha;
    const double b0 = std::erfc(alpha * r) * invr, b1 = (b0 + c) * i2, b2 = (3 * b1 + a2 * c) * i2,
                 b3 = (5 * b2 + a2 * a2 * c) * i2;
    G = b0, F = -b1, H = b2, T = -b3;
  }
};

// Ewald sum (tin-foil) of charges and dipoles in the box of edges L centred at the origin,
// sources = targets (the self terms removed): potential, gradient, second derivatives
Field ewald_dipoles(const Dipoles &s, const double L[3])
{
  const std::size_t n = s.p.size();
  const double Lmin = std::min(L[0], std::min(L[1], L[2])), V = L[0] * L[1] * L[2];
  const double alpha = 4.0 / Lmin, rcut = 6.5 / alpha, kcut = 13.0 * alpha;
  Field f{std::vector<double>(n), std::vector<double>(3 * n), std::vector<double>(6 * n)};
  int nim[3], mk[3];
  for (int d = 0; d < 3; ++d) {
    nim[d] = (int) std::ceil(rcut / L[d]) + 1;
    mk[d] = (int) std::ceil(kcut * L[d] / (2 * kPi));
  }
  std::vector<double> sx(n), sy(n), sz(n), mx(n), my(n), mz(n);
  for (std::size_t j = 0; j < n; ++j) {
    sx[j] = s.p.xyz[3 * j], sy[j] = s.p.xyz[3 * j + 1], sz[j] = s.p.xyz[3 * j + 2];
    mx[j] = s.mu[3 * j], my[j] = s.mu[3 * j + 1], mz[j] = s.mu[3 * j + 2];
  }
  // real space: every image (the pair i, i at n = 0 is masked as r = 0)
  const ErfcKernel ek{alpha};
  for (int a = -nim[0]; a <= nim[0]; ++a)
    for (int b = -nim[1]; b <= nim[1]; ++b)
      for (int c = -nim[2]; c <= nim[2]; ++c) {
        std::vector<double> ix(n), iy(n), iz(n);
        for (std::size_t j = 0; j < n; ++j) ix[j] = sx[j] + a * L[0], iy[j] = sy[j] + b * L[1], iz[j] = sz[j] + c * L[2];
        const kifmm::PointSpan src{n, ix.data(), iy.data(), iz.data(), s.p.q.data(), mx.data(), my.data(), mz.data()};
        std::vector<double> h[6];
        for (auto &v : h) v.assign(n, 0.0);
        std::vector<double> gx(n), gy(n), gz(n), p(n);
        const kifmm::PointSpan trg{n, sx.data(), sy.data(), sz.data()};
        kifmm::p2p_dipole<ErfcKernel, true, true, false>(
            ek, trg, src, {p.data(), gx.data(), gy.data(), gz.data(), h[0].data(), h[1].data(), h[2].data(), h[3].data(),
                           h[4].data(), h[5].data()},
            nullptr);
        for (std::size_t i = 0; i < n; ++i) {
          f.pot[i] += p[i];
          f.grad[3 * i] += gx[i], f.grad[3 * i + 1] += gy[i], f.grad[3 * i + 2] += gz[i];
          for (int m = 0; m < 6; ++m) f.hess[6 * i + m] += h[m][i];
        }
      }
  // reciprocal space: S(k) = sum_j (q_j - i k.mu_j) exp(-i k.y_j)
  const int ia[6] = {0, 1, 2, 0, 0, 1}, ib[6] = {0, 1, 2, 1, 2, 2};
  for (int a = -mk[0]; a <= mk[0]; ++a)
    for (int b = -mk[1]; b <= mk[1]; ++b)
      for (int c = -mk[2]; c <= mk[2]; ++c) {
        if (a == 0 && b == 0 && c == 0) continue;
        const double k[3] = {2 * kPi * a / L[0], 2 * kPi * b / L[1], 2 * kPi * c / L[2]};
        const double k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
        if (k2 > kcut * kcut) continue;
        const double w = 4 * kPi / V * std::exp(-k2 / (4 * alpha * alpha)) / k2;
        double sre = 0, sim = 0;
        for (std::size_t j = 0; j < n; ++j) {
          const double ph = k[0] * sx[j] + k[1] * sy[j] + k[2] * sz[j], km = k[0] * mx[j] + k[1] * my[j] + k[2] * mz[j];
          const double cs = std::cos(ph), sn = std::sin(ph);
          // (q - i km)(cos - i sin) = q cos - km sin - i (q sin + km cos)
          sre += s.p.q[j] * cs - km * sn;
          sim -= s.p.q[j] * sn + km * cs;
        }
        for (std::size_t i = 0; i < n; ++i) {
          const double ph = k[0] * sx[i] + k[1] * sy[i] + k[2] * sz[i], cs = std::cos(ph), sn = std::sin(ph);
          const double re = cs * sre - sn * sim, im = cs * sim + sn * sre;    // e^{ikx} S
          f.pot[i] += w * re;
          for (int d = 0; d < 3; ++d) f.grad[3 * i + d] -= w * k[d] * im;    // Re(i k e^{ikx} S)
          for (int m = 0; m < 6; ++m) f.hess[6 * i + m] -= w * k[ia[m]] * k[ib[m]] * re;
        }
      }
  // self terms of the reciprocal sum
  const double c1 = 2 * alpha / std::sqrt(kPi), c3 = 4 * alpha * alpha * alpha / (3 * std::sqrt(kPi));
  for (std::size_t i = 0; i < n; ++i) {
    f.pot[i] -= c1 * s.p.q[i];
    for (int d = 0; d < 3; ++d) f.grad[3 * i + d] -= c3 * s.mu[3 * i + d];
    for (int d = 0; d < 3; ++d) f.hess[6 * i + d] += c3 * s.p.q[i];
  }
  return f;
}

// periodic boundaries, octree and single-level grid, a cube and rectangular boxes (also 1 cell
// across thin sides): against the Ewald sum (tin-foil; a net charge: its neutralizing background)
TEST(Dipoles, PeriodicEqualsEwald)
{
  struct Box {
    const char *name;
    double shape[3];
    int grid;
    bool neutral;
  };
  for (const Box &b : {Box{"cube, octree", {1, 1, 1}, 0, true}, Box{"cube, grid", {1, 1, 1}, 4, true},
                       Box{"2x1x1, grid", {1, 0.5, 0.5}, 6, true}, Box{"charged, octree", {1, 1, 1}, 0, false},
                       Box{"charged, grid", {1, 1, 1}, 4, false}, Box{"8x8x1, grid", {1, 1, 0.125}, 8, true},
                       Box{"8x1x1, grid", {1, 0.125, 0.125}, 8, true}}) {
    Points pts = uniform_cube(250, 61);
    for (std::size_t i = 0; i < pts.size(); ++i)
      for (int d = 0; d < 3; ++d) pts.xyz[3 * i + d] *= b.shape[d];
    Dipoles s = random_dipoles(b.neutral ? neutral(pts) : pts, 62, true);
    if (!b.neutral)
      for (double &q : s.p.q) q += 0.3;    // net charge: the background's second derivatives
    const double L[3] = {2 * b.shape[0], 2 * b.shape[1], 2 * b.shape[2]};
    const Field ref = ewald_dipoles(s, L);
    kifmm::Options o = periodic_options(10, 32, 1.0, nullptr, b.grid);
    for (int d = 0; d < 3; ++d) o.root_shape[d] = b.shape[d];
    auto ev = kifmm::make_evaluator({}, o);
    const Field f = fmm(*ev, s);
    const double err[3] = {rel_l2(f.pot, ref.pot), rel_l2(f.grad, ref.grad), rel_l2(f.hess, ref.hess)};
    std::printf("%-14s pot %.2e  grad %.2e  hess %.2e\n", b.name, err[0], err[1], err[2]);
    // the engine's own reference (the error check of kspace_style kifmm) is this sum too
    const std::size_t n = s.p.size();
    Field e{std::vector<double>(n), std::vector<double>(3 * n), std::vector<double>(6 * n)};
    const double c0[3] = {0, 0, 0};
    kifmm::periodic_dipole_direct_sum(c0, 1.0, b.shape, n, s.p.xyz.data(), s.p.q.data(), s.mu.data(), n,
                                      s.p.xyz.data(), e.pot.data(), e.grad.data(), e.hess.data());
    if (b.neutral) EXPECT_LT(rel_l2(e.pot, ref.pot), 1e-12) << b.name;
    EXPECT_LT(rel_l2(e.grad, ref.grad), 1e-12) << b.name;
    EXPECT_LT(rel_l2(e.hess, ref.hess), 1e-12) << b.name;
    if (b.neutral) EXPECT_LT(err[0], 1e-7) << b.name;    // net charge: potentials differ by a constant
    EXPECT_LT(err[1], 1e-7) << b.name;
    EXPECT_LT(err[2], 1e-7) << b.name;
  }
}

}    // namespace

namespace {

double ewald_energy(const Dipoles &s, const double L[3])
{
  const Field f = ewald_dipoles(s, L);
  double e = 0;
  for (std::size_t i = 0; i < s.p.size(); ++i) {
    e += s.p.q[i] * f.pot[i];
    for (int d = 0; d < 3; ++d) e += s.mu[3 * i + d] * f.grad[3 * i + d];
  }
  return 0.5 * e;
}

// the virial tensor (xx yy zz xy xz yz) of charges and dipoles from the evaluator of these options
std::vector<double> dipole_virial_total(const kifmm::Options &o, const Dipoles &s)
{
  const std::size_t n = s.p.size();
  auto ev = kifmm::make_evaluator({}, o);
  const Field f = fmm(*ev, s);
  std::vector<double> v(6 * n), W(6, 0.0);
  kifmm::periodic_dipole_point_virial(*ev, n, s.p.xyz.data(), s.p.q.data(), s.mu.data(), n, s.p.xyz.data(),
                                      s.p.q.data(), s.mu.data(), f.grad.data(), f.hess.data(), -1.0, v.data());
  for (std::size_t k = 0; k < n; ++k)
    for (int m = 0; m < 6; ++m) W[m] += v[6 * k + m];
  return W;
}

// -dU/d(strain_aa) by central differences (strain 1e-5) of energy(dipoles, cell edges): the
// positions along axis a scaled, and the edge a when stretch_edge; moments fixed
template <class Energy>
double minus_strain_derivative(const Dipoles &s, const double L[3], int a, bool stretch_edge, const Energy &energy)
{
  const double eps = 1e-5;
  double de[2];
  for (int sg : {1, -1}) {
    Dipoles t = s;
    double Lt[3] = {L[0], L[1], L[2]};
    if (stretch_edge) Lt[a] *= 1 + sg * eps;
    for (std::size_t k = 0; k < t.p.size(); ++k) t.p.xyz[3 * k + a] *= 1 + sg * eps;
    de[sg > 0 ? 0 : 1] = energy(t, Lt);
  }
  return -(de[0] - de[1]) / (2 * eps);
}

// the periodic virial of charges and dipoles (grid, order 12: the dipoles' virial converges
// more slowly with the order than their forces): its diagonal is minus the derivative of the
// Ewald energy under a stretch of one axis (positions scaled, moments fixed)
TEST(Dipoles, PeriodicVirialIsTheStrainDerivative)
{
  for (const double sy : {1.0, 0.5, 0.125}) {
    Points pts = uniform_cube(120, 71);
    const double shape[3] = {1.0, sy, 1.0};
    for (std::size_t i = 0; i < pts.size(); ++i) pts.xyz[3 * i + 1] *= sy;
    const Dipoles s = random_dipoles(neutral(pts), 72, true);
    kifmm::Options o = periodic_options(12, 32, 1.0, nullptr, sy == 1.0 ? 4 : sy == 0.5 ? 6 : 8);    // 0.125: 8 x 1 x 8
    for (int d = 0; d < 3; ++d) o.root_shape[d] = shape[d];
    const std::vector<double> W = dipole_virial_total(o, s);
    const double L[3] = {2.0, 2.0 * sy, 2.0};
    for (int a = 0; a < 3; ++a) {
      const double w = minus_strain_derivative(s, L, a, true, ewald_energy);
      std::printf("shape y %.3f: W_%d%d %.10f, -dU/de %.10f\n", sy, a, a, W[a], w);
      EXPECT_NEAR(W[a], w, 1e-8 * (std::fabs(W[0]) + std::fabs(W[1]) + std::fabs(W[2]))) << "axis " << a;
    }
  }
}

// the slab virial of charges and dipoles: against strain derivatives of the slab energy, taken
// as the 3-d Ewald energy of the cell with a vacuum of 14 cell widths in z plus the correction
// of Yeh and Berkowitz, 2 pi M_z^2 / V (M the total dipole moment, charges' and point dipoles'):
// for neutral charges that is the doubly periodic energy up to terms that decay as exp(-k gap).
// x, y: the cell and the positions stretched; z: the positions (the vacuum stays).
TEST(Dipoles, SlabVirialIsTheStrainDerivative)
{
  const double shape[3] = {1.0, 0.7, 0.5};
  Points pts = uniform_cube(120, 73);
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (int d = 0; d < 3; ++d) pts.xyz[3 * i + d] *= shape[d];
  const Dipoles s = random_dipoles(neutral(pts), 74, true);
  kifmm::Options o = periodic_options(12, 32, 1.0, nullptr, kifmm::choose_slab_grid(12, s.p.size(), shape).grid);
  o.periodic_dims = 2;
  for (int d = 0; d < 3; ++d) o.root_shape[d] = shape[d];
  const std::vector<double> W = dipole_virial_total(o, s);
  auto slab_energy = [](const Dipoles &t, const double Lt[3]) {
    double Mz = 0;
    for (std::size_t k = 0; k < t.p.size(); ++k) Mz += t.p.q[k] * t.p.xyz[3 * k + 2] + t.mu[3 * k + 2];
    return ewald_energy(t, Lt) + 2 * kPi * Mz * Mz / (Lt[0] * Lt[1] * Lt[2]);
  };
  const double L[3] = {2.0, 2.0 * shape[1], 2.0 * shape[2] + 28.0};
  for (int a = 0; a < 3; ++a) {
    const double w = minus_strain_derivative(s, L, a, a < 2, slab_energy);
    std::printf("slab: W_%d%d %.10f, -dU/de %.10f\n", a, a, W[a], w);
    EXPECT_NEAR(W[a], w, 1e-7 * (std::fabs(W[0]) + std::fabs(W[1]) + std::fabs(W[2]))) << "axis " << a;
  }
}

}    // namespace

namespace {

// slabs (periodic in x and y, open in z; grid): a dipole is the limit of a charge pair, so the
// exact doubly periodic sum of charge pairs (slab_direct_sum; pairs of separation e and e/2,
// extrapolated: error O(e^4)) is the reference at targets away from the sources; second
// derivatives against central differences of that reference (extrapolated in the step too)
TEST(Dipoles, SlabEqualsTheLimitOfChargePairs)
{
  const double c[3] = {0.5, -1.0, 2.0}, h = 1.5, shape[3] = {1.0, 1.0, 0.5};
  auto place = [&](Points p) {
    for (std::size_t i = 0; i < p.size(); ++i)
      for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] = c[d] + h * shape[d] * p.xyz[3 * i + d];
    return p;
  };
  const Dipoles s = random_dipoles(place(neutral(uniform_cube(100, 81))), 82, true);
  const Points t = targets_away_from(s, place(uniform_cube(200, 83)), 25, 0.1);
  const Points p1 = charge_pairs(s, 2e-4), p2 = charge_pairs(s, 1e-4);
  auto slab_ref = [&](const Points &tt, std::vector<double> &pot, std::vector<double> &grad) {
    std::vector<double> a(tt.size()), ga(3 * tt.size()), b(tt.size()), gb(3 * tt.size());
    kifmm::slab_direct_sum(c, h, shape, p1.size(), p1.xyz.data(), p1.q.data(), tt.size(), tt.xyz.data(), a.data(),
                           ga.data());
    kifmm::slab_direct_sum(c, h, shape, p2.size(), p2.xyz.data(), p2.q.data(), tt.size(), tt.xyz.data(), b.data(),
                           gb.data());
    pot.resize(tt.size());
    grad.resize(3 * tt.size());
    for (std::size_t i = 0; i < a.size(); ++i) pot[i] = (4 * b[i] - a[i]) / 3;
    for (std::size_t i = 0; i < ga.size(); ++i) grad[i] = (4 * gb[i] - ga[i]) / 3;
  };
  std::vector<double> rp, rg;
  slab_ref(t, rp, rg);
  std::vector<double> rh(6 * t.size());
  const int hc[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
  for (int b = 0; b < 3; ++b) {
    double dv[2][120];    // central differences of the gradient with steps 2f and f
    for (int level = 0; level < 2; ++level) {
      const double fd = level == 0 ? 2e-3 : 1e-3;
      Points tp = t, tm = t;
      for (std::size_t i = 0; i < t.size(); ++i) tp.xyz[3 * i + b] += fd, tm.xyz[3 * i + b] -= fd;
      std::vector<double> pp, gp, pm, gm;
      slab_ref(tp, pp, gp);
      slab_ref(tm, pm, gm);
      for (std::size_t k = 0; k < 3 * t.size(); ++k) dv[level][k] = (gp[k] - gm[k]) / (2 * fd);
    }
    for (std::size_t i = 0; i < t.size(); ++i)
      for (int a = 0; a <= b; ++a) rh[6 * i + hc[a][b]] = (4 * dv[1][3 * i + a] - dv[0][3 * i + a]) / 3;
  }
  kifmm::Options o = periodic_options(10, 40, h, c, 6);
  o.periodic_dims = 2;
  for (int d = 0; d < 3; ++d) o.root_shape[d] = shape[d];
  auto ev = kifmm::make_evaluator({}, o);
  std::vector<double> pot(t.size()), grad(3 * t.size()), hess(6 * t.size());
  ev->evaluate_dipoles(s.p.size(), s.p.xyz.data(), s.p.q.data(), s.mu.data(), t.size(), t.xyz.data(), pot.data(),
                       grad.data(), hess.data());
  const double err[3] = {rel_l2(pot, rp), rel_l2(grad, rg), rel_l2(hess, rh)};
  std::printf("slab (%zu targets): pot %.2e  grad %.2e  hess %.2e\n", t.size(), err[0], err[1], err[2]);
  // order 10 in a slab: 1e-7 (at order 13 these errors are 1e-10, 3e-10 and 4e-8: the reference's)
  EXPECT_LT(err[0], 3e-7);
  EXPECT_LT(err[1], 5e-7);
  EXPECT_LT(err[2], 2e-6);
}

}    // namespace

namespace {

// periodic yukawa (no Ewald sum of dipoles is written for it): the extrapolated limit of charge
// pairs in the exact periodic sum of charges (periodic_direct_sum), at targets away from the
// sources; octree and grid
TEST(Dipoles, PeriodicYukawaEqualsTheLimitOfChargePairs)
{
  const double c[3] = {0, 0, 0};
  const kifmm::KernelSpec k = yukawa(1.5);
  const Dipoles s = random_dipoles(neutral(uniform_cube(150, 91)), 92, true);
  const Points t = targets_away_from(s, uniform_cube(200, 93), 30, 0.1);
  std::vector<double> ref[2];
  for (int level = 0; level < 2; ++level) {
    const Points pair = charge_pairs(s, level == 0 ? 2e-4 : 1e-4);
    ref[level].resize(3 * t.size());
    kifmm::periodic_direct_sum(k, c, 1.0, pair.size(), pair.xyz.data(), pair.q.data(), t.size(), t.xyz.data(),
                               nullptr, ref[level].data());
  }
  std::vector<double> rg(3 * t.size());
  for (std::size_t i = 0; i < rg.size(); ++i) rg[i] = (4 * ref[1][i] - ref[0][i]) / 3;
  for (int grid : {0, 4}) {
    auto ev = kifmm::make_evaluator(k, periodic_options(10, 32, 1.0, nullptr, grid));
    std::vector<double> grad(3 * t.size()), hess(6 * t.size());
    ev->evaluate_dipoles(s.p.size(), s.p.xyz.data(), s.p.q.data(), s.mu.data(), t.size(), t.xyz.data(), nullptr,
                         grad.data(), hess.data());
    const double err = rel_l2(grad, rg);
    std::printf("periodic yukawa, %s: grad %.2e\n", grid ? "grid" : "octree", err);
    EXPECT_LT(err, 1e-7) << grid;
  }
}

}    // namespace
