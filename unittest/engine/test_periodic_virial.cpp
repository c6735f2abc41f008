// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The virial tensor of periodic systems (kifmm::periodic_point_virial, single-level grid,
// Laplace): per point against an Ewald sum of the pair virial written here (real-space and
// reciprocal parts of sum_n (r_n)_a dG/dr_b(r_n), with the background constant), its trace
// against the energy, its diagonal against numerical derivatives of the exact energy under
// small anisotropic strains; cubic and rectangular boxes, neutral and charged; slabs (p p f)
// against the doubly periodic Ewald sum and the strain derivatives of its energy; yukawa against
// the image sum of the pair virial and the strain derivatives of its lattice energy.
#include "periodic.h"

#include "fmm_core.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <complex>
#include <stdexcept>

using namespace kifmm_test;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Ewald reference: v_i,ab = 1/2 q_i sum_j q_j K_ab(x_i - x_j) (prefactor 1), K_ab(r) the
// strain derivative of the tin-foil G_per: real space sum_n (r_n)_a (r_n)_b g'(r_n)/r_n with
// g = erfc(alpha r)/r (n = 0 left out for i = j), reciprocal (4 pi / V) sum_k exp(-k^2/4 alpha^2)
// / k^2 cos(k.r) [-delta_ab + 2 k_a k_b (1/(4 alpha^2) + 1/k^2)], constant delta_ab pi/(V alpha^2).
std::vector<double> ewald_point_virial(const Points &p, const double L[3])
{
  const std::size_t n = p.size();
  const double Lmin = std::min(L[0], std::min(L[1], L[2])), V = L[0] * L[1] * L[2];
  const double alpha = 4.0 / Lmin, rcut = 6.5 / alpha, kcut = 13.0 * alpha;
  std::vector<double> T(9 * n, 0.0);
  int nim[3], mk[3];
  for (int d = 0; d < 3; ++d) {
    nim[d] = (int) std::ceil(rcut / L[d]) + 1;
    mk[d] = (int) std::ceil(kcut * L[d] / (2 * kPi));
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (int a = -nim[0]; a <= nim[0]; ++a)
        for (int b = -nim[1]; b <= nim[1]; ++b)
          for (int c = -nim[2]; c <= nim[2]; ++c) {
            if (i == j && a == 0 && b == 0 && c == 0) continue;
            const int m[3] = {a, b, c};
            double r[3], r2 = 0;
            for (int d = 0; d < 3; ++d) {
              r[d] = p.xyz[3 * i + d] - p.xyz[3 * j + d] + m[d] * L[d];
              r2 += r[d] * r[d];
            }
            const double rho = std::sqrt(r2);
            if (rho > rcut) continue;
            const double F = (-std::erfc(alpha * rho) / rho - 2 * alpha / std::sqrt(kPi) * std::exp(-alpha * alpha * r2)) /
                (rho * rho);    // g'(rho) / rho
            for (int x = 0; x < 3; ++x)
              for (int y = 0; y < 3; ++y) T[9 * i + 3 * x + y] += p.q[j] * r[x] * r[y] * F;
          }
  for (int a = -mk[0]; a <= mk[0]; ++a)
    for (int b = -mk[1]; b <= mk[1]; ++b)
      for (int c = -mk[2]; c <= mk[2]; ++c) {
        if (a == 0 && b == 0 && c == 0) continue;
        const double k[3] = {2 * kPi * a / L[0], 2 * kPi * b / L[1], 2 * kPi * c / L[2]};
        const double k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
        if (k2 > kcut * kcut) continue;
        const double f = 4 * kPi / V * std::exp(-k2 / (4 * alpha * alpha)) / k2, h = 2 * (1 / (4 * alpha * alpha) + 1 / k2);
        std::complex<double> S = 0;
        for (std::size_t j = 0; j < n; ++j)
          S += p.q[j] * std::polar(1.0, k[0] * p.xyz[3 * j] + k[1] * p.xyz[3 * j + 1] + k[2] * p.xyz[3 * j + 2]);
        for (std::size_t i = 0; i < n; ++i) {
          const double cs =
              (std::polar(1.0, k[0] * p.xyz[3 * i] + k[1] * p.xyz[3 * i + 1] + k[2] * p.xyz[3 * i + 2]) * std::conj(S)).real();
          for (int x = 0; x < 3; ++x)
            for (int y = 0; y < 3; ++y) T[9 * i + 3 * x + y] += f * cs * ((x == y ? -1.0 : 0.0) + h * k[x] * k[y]);
        }
      }
  double Q = 0;
  for (double s : p.q) Q += s;
  std::vector<double> v(6 * n);
  const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  for (std::size_t i = 0; i < n; ++i)
    for (int m = 0; m < 6; ++m) {
      const int a = ab[m][0], b = ab[m][1];
      const double K = T[9 * i + 3 * a + b] + (a == b ? Q * kPi / (V * alpha * alpha) : 0.0);
      v[6 * i + m] = 0.5 * p.q[i] * K;
    }
  return v;
}

struct Case {
  double shape[3];
  double shift;    // added to every charge (net charge)
};

Points case_points(std::size_t n, unsigned seed, const double c[3], double h, const double shape[3], double shift)
{
  Points p = uniform_cube(n, seed);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] = c[d] + h * shape[d] * p.xyz[3 * i + d];
    p.q[i] += shift;
  }
  return p;
}

// the fewest grid cells (3 .. 12 along the longest side) that fit the cell at order 10; 0: none
int fitting_grid(const double shape[3])
{
  for (int k = 3; k <= 12; ++k)
    if (kifmm::grid_fits_cell(10, k, shape)) return k;
  return 0;
}

kifmm::Options grid_options(int order, int grid, double h, const double c[3], const double shape[3])
{
  kifmm::Options o = periodic_options(order, 32, h, c, grid);
  for (int d = 0; d < 3; ++d) o.root_shape[d] = shape[d];
  return o;
}

std::vector<double> fmm_point_virial(const kifmm::Options &o, const Points &p, const kifmm::KernelSpec &kernel = {})
{
  const std::size_t n = p.size();
  auto ev = kifmm::make_evaluator(kernel, o);
  std::vector<double> g(3 * n), v(6 * n);
  ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), nullptr, g.data());
  kifmm::periodic_point_virial(*ev, nullptr, n, p.xyz.data(), p.q.data(), g.data(), 1.0, v.data());
  return v;
}

std::vector<double> total(const std::vector<double> &v)
{
  std::vector<double> t(6, 0.0);
  for (std::size_t i = 0; i < v.size(); ++i) t[i % 6] += v[i];
  return t;
}

// The virial tensor W (xx yy zz xy xz yz) and the energy U = 1/2 sum q phi of the evaluator of
// these options (prefactor -1: F = -q grad, the force for U)
struct GlobalVirial {
  std::vector<double> W;
  double U = 0;
};
GlobalVirial global_virial(const kifmm::KernelSpec &kernel, const kifmm::Options &o, const Points &p)
{
  const std::size_t n = p.size();
  auto ev = kifmm::make_evaluator(kernel, o);
  std::vector<double> g(3 * n), pot(n), v(6 * n);
  ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
  kifmm::periodic_point_virial(*ev, nullptr, n, p.xyz.data(), p.q.data(), g.data(), -1.0, v.data());
  GlobalVirial r{total(v), 0.0};
  for (std::size_t i = 0; i < n; ++i) r.U += 0.5 * p.q[i] * pot[i];
  return r;
}

// dU/d(strain_aa) by central differences (strain 1e-4) of an exact lattice energy: the points
// and the cell (half-widths h shape, centre c) stretched along `axis` about c; `potentials`
// gives the exact potentials of points in the cell of largest half-width H and shape sh
using LatticePotentials =
    std::function<void(const double c[3], double H, const double sh[3], const Points &p, double *pot)>;
double strain_derivative(const Points &p, const double c[3], double h, const double shape[3], int axis,
                         const LatticePotentials &potentials)
{
  const std::size_t n = p.size();
  auto energy = [&](double eps) {
    Points s = p;
    double sh[3] = {shape[0], shape[1], shape[2]};
    for (std::size_t i = 0; i < n; ++i) s.xyz[3 * i + axis] = c[axis] + (s.xyz[3 * i + axis] - c[axis]) * (1 + eps);
    sh[axis] *= 1 + eps;
    const double hs = std::max(sh[0], std::max(sh[1], sh[2]));
    for (double &x : sh) x /= hs;
    std::vector<double> ps(n);
    potentials(c, h * hs, sh, s, ps.data());
    double u = 0;
    for (std::size_t i = 0; i < n; ++i) u += 0.5 * s.q[i] * ps[i];
    return u;
  };
  const double eps = 1e-4;
  return (energy(eps) - energy(-eps)) / (2 * eps);
}

LatticePotentials ewald_potentials(const kifmm::KernelSpec &kernel)
{
  return [kernel](const double c[3], double H, const double sh[3], const Points &s, double *pot) {
    kifmm::periodic_direct_sum(kernel, c, H, s.size(), s.xyz.data(), s.q.data(), s.size(), s.xyz.data(), pot, nullptr, sh);
  };
}

}    // namespace

TEST(PeriodicVirial, PerPointEqualsEwald)
{
  const double c[3] = {0.1, -0.2, 0.3}, h = 0.5;
  for (const Case &cs : {Case{{1.0, 1.0, 1.0}, 0.0}, Case{{1.0, 0.8, 0.9}, 0.0}, Case{{1.0, 0.6, 0.6}, 0.15}}) {
    const Points p = case_points(300, 7, c, h, cs.shape, cs.shift);
    const int grid = fitting_grid(cs.shape);
    ASSERT_GT(grid, 0) << cs.shape[1] << " " << cs.shape[2];
    const std::vector<double> v = fmm_point_virial(grid_options(10, grid, h, c, cs.shape), p);
    const double L[3] = {2 * h * cs.shape[0], 2 * h * cs.shape[1], 2 * h * cs.shape[2]};
    const std::vector<double> ref = ewald_point_virial(p, L);
    const double e = rel_l2(v, ref), et = rel_l2(total(v), total(ref));
    EXPECT_LT(e, 1e-6) << cs.shape[1] << " " << cs.shape[2] << " shift " << cs.shift;
    EXPECT_LT(et, 1e-6) << cs.shape[1] << " " << cs.shape[2] << " shift " << cs.shift;
    // the off-diagonal part is not small: the test sees it
    const std::vector<double> t = total(ref);
    EXPECT_GT(std::fabs(t[3]) + std::fabs(t[4]) + std::fabs(t[5]), 1e-3 * (std::fabs(t[0]) + std::fabs(t[1]) + std::fabs(t[2])));
  }
}

TEST(PeriodicVirial, TraceIsTheEnergyAndDiagonalIsTheStrainDerivative)
{
  // U = 1/2 sum q_i phi_i; W_aa = -dU/d(strain_aa) at fixed scaled coordinates, by central
  // differences of the exact (Ewald) energy of the strained box
  const double c[3] = {0, 0, 0}, h = 0.5, shape[3] = {1.0, 0.7, 0.85};
  const Points p = case_points(200, 11, c, h, shape, 0.05);
  const int grid = fitting_grid(shape);
  ASSERT_GT(grid, 0);
  const GlobalVirial g = global_virial(kifmm::KernelSpec{}, grid_options(10, grid, h, c, shape), p);
  const std::vector<double> &W = g.W;
  const double U = g.U;
  EXPECT_NEAR(W[0] + W[1] + W[2], U, 1e-7 * std::fabs(U));
  for (int a = 0; a < 3; ++a) {
    const double dU = strain_derivative(p, c, h, shape, a, ewald_potentials(kifmm::KernelSpec{}));
    EXPECT_NEAR(W[a], -dU, 1e-6 * std::fabs(U)) << "axis " << a;
  }
  // anisotropic: the diagonal components differ
  EXPECT_GT(std::fabs(W[0] - W[1]) + std::fabs(W[1] - W[2]), 1e-3 * std::fabs(U));
}

// ---------------------------------------------------------------- slabs (p p f)

kifmm::Options slab_grid_options(int order, std::size_t n, double h, const double c[3], const double shape[3])
{
  kifmm::Options o = grid_options(order, kifmm::choose_slab_grid(order, n, shape).grid, h, c, shape);
  o.periodic_dims = 2;
  return o;
}

// Per point, against references independent of the grid: the components with a z index from
// the doubly periodic Ewald sum (no images in z: v_i,zb = 1/2 q_i sum_j q_j (z_i - z_j) d_b G_2 =
// 1/2 q_i (z_i g_b[q] - g_b[q z])); v_xy against the 3-d Ewald point virial of the cell with a
// vacuum of 14 cell widths in z (the tin-foil sum differs from the slab by a uniform field along
// z, which has no xy part, and by images whose fields decay as exp(-k gap)).
TEST(PeriodicVirial, SlabPerPointEqualsTheDoublyPeriodicSum)
{
  const double c[3] = {0.1, -0.2, 0.3}, h = 1.0, shape[3] = {1.0, 0.8, 0.4};
  Points p = case_points(300, 17, c, h, shape, 0.0);
  double Q = 0;
  for (double q : p.q) Q += q;
  for (double &q : p.q) q -= Q / p.size();    // neutral (the 3-d reference's own convention for Q)
  const std::size_t n = p.size();
  const kifmm::Options o = slab_grid_options(10, n, h, c, shape);
  const std::vector<double> v = fmm_point_virial(o, p);
  // z components
  std::vector<double> qz(n), g(3 * n), gz(3 * n);
  for (std::size_t i = 0; i < n; ++i) qz[i] = p.q[i] * p.xyz[3 * i + 2];
  kifmm::slab_direct_sum(c, h, shape, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), nullptr, g.data());
  kifmm::slab_direct_sum(c, h, shape, n, p.xyz.data(), qz.data(), n, p.xyz.data(), nullptr, gz.data());
  std::vector<double> vz(3 * n), rz(3 * n);
  const int zm[3] = {4, 5, 2};    // xz, yz, zz
  for (std::size_t i = 0; i < n; ++i)
    for (int b = 0; b < 3; ++b) {
      vz[3 * i + b] = v[6 * i + zm[b]];
      rz[3 * i + b] = 0.5 * p.q[i] * (p.xyz[3 * i + 2] * g[3 * i + b] - gz[3 * i + b]);
    }
  const double ez = rel_l2(vz, rz);
  // xy
  const double L[3] = {2 * h * shape[0], 2 * h * shape[1], 2 * h * shape[2] + 14 * 2 * h * shape[0]};
  const std::vector<double> ref = ewald_point_virial(p, L);
  std::vector<double> vxy(n), rxy(n);
  for (std::size_t i = 0; i < n; ++i) {
    vxy[i] = v[6 * i + 3];
    rxy[i] = ref[6 * i + 3];
  }
  const double exy = rel_l2(vxy, rxy);
  std::printf("  slab per-point virial: z components %.2e, xy %.2e\n", ez, exy);
  EXPECT_LT(ez, 1e-6);
  EXPECT_LT(exy, 1e-6);
  double sxy = 0, sd = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxy += std::fabs(rxy[i]);
    sd += std::fabs(v[6 * i]);
  }
  EXPECT_GT(sxy, 1e-2 * sd) << "the xy part is not small";
}

// The global slab virial: trace = energy (degree -1), W_aa = -dU/d(strain_aa) by central
// differences of the doubly periodic Ewald energy (x, y: the cell and the points; z: the
// points), neutral and with a net charge (taken without background).
TEST(PeriodicVirial, SlabDiagonalIsTheStrainDerivative)
{
  const double c[3] = {0, 0, 0}, h = 1.0, shape[3] = {1.0, 0.7, 0.5};
  for (double shift : {0.0, 0.08}) {
    Points p = case_points(200, 23, c, h, shape, 0.0);
    double Q = 0;
    for (double q : p.q) Q += q;
    for (double &q : p.q) q += shift - Q / p.size();
    const std::size_t n = p.size();
    const GlobalVirial gv = global_virial(kifmm::KernelSpec{}, slab_grid_options(10, n, h, c, shape), p);
    const std::vector<double> &W = gv.W;
    const double U = gv.U;
    EXPECT_NEAR(W[0] + W[1] + W[2], U, 1e-7 * std::fabs(U)) << "shift " << shift;
    const LatticePotentials slab = [](const double cc[3], double H, const double sh[3], const Points &s, double *pot) {
      kifmm::slab_direct_sum(cc, H, sh, s.size(), s.xyz.data(), s.q.data(), s.size(), s.xyz.data(), pot, nullptr);
    };
    double dU[3];
    for (int a = 0; a < 3; ++a) {
      dU[a] = strain_derivative(p, c, h, shape, a, slab);
      EXPECT_NEAR(W[a], -dU[a], 1e-6 * std::fabs(U)) << "axis " << a << " shift " << shift;
    }
    std::printf("  slab virial (net charge %.2f): W %.8g %.8g %.8g, -dU/de %.8g %.8g %.8g, U %.8g\n", shift * n, W[0], W[1],
                W[2], -dU[0], -dU[1], -dU[2], U);
    EXPECT_GT(std::fabs(W[0] - W[1]) + std::fabs(W[1] - W[2]), 1e-3 * std::fabs(U));
  }
}

// ---------------------------------------------------------------- yukawa (p p p)

// Per point against the image sum of the pair virial (the screened kernel converges absolutely:
// images |n_d| <= 5 leave exp(-kappa 8 h) < 1e-10), charges with a net part (no background for
// yukawa); the diagonal of the total against central differences of the exact lattice energy
// (periodic_direct_sum) under stretches of one axis at fixed kappa. The trace is not the energy
// (the kernel is not homogeneous).
TEST(PeriodicVirial, YukawaPerPointEqualsTheImageSumAndDiagonalIsTheStrainDerivative)
{
  const double c[3] = {0.1, -0.2, 0.3}, h = 1.0, shape[3] = {1.0, 0.8, 0.9}, kappa = 3.0;
  const kifmm::KernelSpec yk{kifmm::KernelType::Yukawa, kappa};
  const Points p = case_points(200, 19, c, h, shape, 0.1);
  const std::size_t n = p.size();
  const int grid = fitting_grid(shape);
  ASSERT_GT(grid, 0);
  const kifmm::Options o = grid_options(10, grid, h, c, shape);
  const std::vector<double> v = fmm_point_virial(o, p, yk);
  const double L[3] = {2 * h * shape[0], 2 * h * shape[1], 2 * h * shape[2]};
  std::vector<double> ref(6 * n, 0.0);
  const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (int a = -5; a <= 5; ++a)
        for (int b = -5; b <= 5; ++b)
          for (int e = -5; e <= 5; ++e) {
            if (i == j && a == 0 && b == 0 && e == 0) continue;
            const int m[3] = {a, b, e};
            double r[3], r2 = 0;
            for (int d = 0; d < 3; ++d) {
              r[d] = p.xyz[3 * i + d] - p.xyz[3 * j + d] + m[d] * L[d];
              r2 += r[d] * r[d];
            }
            const double rr = std::sqrt(r2), F = -std::exp(-kappa * rr) * (1 + kappa * rr) / (r2 * rr);
            for (int k = 0; k < 6; ++k) ref[6 * i + k] += 0.5 * p.q[i] * p.q[j] * r[ab[k][0]] * r[ab[k][1]] * F;
          }
  const double e = rel_l2(v, ref), et = rel_l2(total(v), total(ref));
  std::printf("  yukawa per-point virial %.2e, total %.2e\n", e, et);
  EXPECT_LT(e, 1e-6);
  EXPECT_LT(et, 1e-6);
  // the diagonal: W_aa = -dU/d(strain_aa)
  const std::vector<double> W = global_virial(yk, o, p).W;
  const double scale = std::fabs(W[0]) + std::fabs(W[1]) + std::fabs(W[2]);
  for (int a = 0; a < 3; ++a) {
    const double dU = strain_derivative(p, c, h, shape, a, ewald_potentials(yk));
    std::printf("  yukawa W_%d%d %.10g, -dU/de %.10g\n", a, a, W[a], -dU);
    EXPECT_NEAR(W[a], -dU, 1e-6 * scale) << "axis " << a;
  }
}

TEST(PeriodicVirial, NeedsThePeriodicGrid)
{
  const double c[3] = {0, 0, 0}, one[3] = {1, 1, 1};
  const Points p = case_points(50, 3, c, 1.0, one, 0.0);
  std::vector<double> g(150), v(300);
  auto octree = kifmm::make_evaluator(kifmm::KernelSpec{}, periodic_options(6, 16, 1.0, c));
  EXPECT_THROW(kifmm::periodic_point_virial(*octree, nullptr, 50, p.xyz.data(), p.q.data(), g.data(), 1.0, v.data()),
               std::invalid_argument);
  kifmm::Options open;
  open.order = 6;
  auto free_space = kifmm::make_evaluator(kifmm::KernelSpec{kifmm::KernelType::Yukawa, 2.0}, open);
  EXPECT_THROW(kifmm::periodic_point_virial(*free_space, nullptr, 50, p.xyz.data(), p.q.data(), g.data(), 1.0, v.data()),
               std::invalid_argument);
}
