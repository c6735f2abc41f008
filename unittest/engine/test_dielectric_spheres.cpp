// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Dielectric spheres by the boundary integral equation (kifmm::polarize_dielectric_spheres)
// against an independent reference written for these tests: the axisymmetric multipole
// solution of two spheres in a field along their line of centres (exterior Legendre series of
// each sphere, re-expanded about the other, the interface conditions degree by degree, a dense
// solve), converged in its number of degrees. Also: one sphere against the closed form, the FMM
// against the direct sum, bad input.
#include "kifmm.h"
#include "sphere_grid.h"
#include "two_dielectric_spheres.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace {

const double kPi = std::acos(-1.0);

// two spheres of radius a, centres d apart along the unit vector `axis`, field E0 along it:
// the force on the first sphere along the axis, by the BIE
double bie_force(kifmm::Evaluator *ev, double a, double d, double eps, const double axis[3], int degree,
                 kifmm::DielectricSphereSolve *keep = nullptr, double refinement = 0.0)
{
  const double c[6] = {0.3 + 0.5 * d * axis[0], -0.2 + 0.5 * d * axis[1], 0.1 + 0.5 * d * axis[2],
                       0.3 - 0.5 * d * axis[0], -0.2 - 0.5 * d * axis[1], 0.1 - 0.5 * d * axis[2]};
  const double r[2] = {a, a}, e[2] = {eps, eps}, E[3] = {axis[0], axis[1], axis[2]};
  kifmm::DielectricSphereOptions opt;
  opt.degree = degree;
  opt.tolerance = 1e-11;
  opt.contact_refinement = refinement;
  const kifmm::DielectricSphereSolve s = kifmm::polarize_dielectric_spheres(ev, 2, c, r, e, E, opt);
  EXPECT_TRUE(s.converged) << s.residual;
  for (int d2 = 0; d2 < 3; ++d2) EXPECT_NEAR(s.force[d2], -s.force[3 + d2], 1e-9);    // Newton's third law
  if (keep) *keep = s;
  return s.force[0] * axis[0] + s.force[1] * axis[1] + s.force[2] * axis[2];
}

}    // namespace

TEST(DielectricSpheres, HarmonicsAreOrthonormalOnTheGrid)
{
  const kifmm::SphereGrid g(7);
  const int nh = kifmm::harmonic_count(7);
  double worst = 0;
  for (int h1 = 0; h1 < nh; ++h1)
    for (int h2 = 0; h2 < nh; ++h2) {
      double s = 0;
      for (std::size_t k = 0; k < g.nodes; ++k) s += g.weight[k] * g.harmonics[k * nh + h1] * g.harmonics[k * nh + h2];
      worst = std::max(worst, std::fabs(s - (h1 == h2)));
    }
  EXPECT_LT(worst, 1e-13);
}

TEST(DielectricSpheres, OneSphereHasTheClosedFormSolution)
{
  const double c[3] = {0.5, -1, 2}, r = 1.7, eps = 5, E[3] = {0.3, -0.4, 1.2};
  kifmm::DielectricSphereOptions opt;
  opt.degree = 4;
  opt.tolerance = 1e-13;
  const auto s = kifmm::polarize_dielectric_spheres(nullptr, 1, c, &r, &eps, E, opt);
  const double beta = (eps - 1) / (eps + 2);
  double worst = 0;
  for (std::size_t k = 0; k < s.nodes_per_sphere; ++k) {
    double en = 0;
    for (int d = 0; d < 3; ++d) en += E[d] * (s.node_xyz[3 * k + d] - c[d]) / r;
    worst = std::max(worst, std::fabs(s.sigma[k] - 3 * beta * en));
  }
  EXPECT_LT(worst, 1e-12);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(s.dipole[d], 4 * kPi * beta * r * r * r * E[d], 1e-11);
    EXPECT_NEAR(s.force[d], 0.0, 1e-12);
  }
}

TEST(DielectricSpheres, ReferenceHasTheDipoleLimit)
{
  // far apart: the force of two induced point dipoles p = 4 pi beta a^3 E0, 6 p^2 / (4 pi d^4)
  const double eps = 10, beta = (eps - 1) / (eps + 2), d = 40, p = 4 * kPi * beta;
  EXPECT_NEAR(kifmm_points::two_sphere_force(1, d, eps, 1, 20) / (-6 * p * p / (4 * kPi * std::pow(d, 4))), 1.0, 1e-3);
}

TEST(DielectricSpheres, SeparatedSpheresMatchTheReference)
{
  // gaps of 0.5 and 0.1 radii, permittivity ratio 10: the error falls spectrally with the degree
  const double axis[3] = {1.0 / 3, 2.0 / 3, -2.0 / 3};
  struct Case {
    double d;
    int degree;
    double tol;
  };
  for (const Case &c : {Case{2.5, 8, 1e-4}, Case{2.5, 12, 1e-7}, Case{2.1, 12, 1e-5}}) {
    const double ref = kifmm_points::two_sphere_force(1, c.d, 10, 1, 200), f = bie_force(nullptr, 1, c.d, 10, axis, c.degree);
    EXPECT_LT(std::fabs(f / ref - 1), c.tol) << "d " << c.d << " degree " << c.degree << ": " << f << " against " << ref;
  }
}

TEST(DielectricSpheres, TouchingSpheresMatchTheReference)
{
  // touching spheres, permittivity ratio 10, the field along their line of centres: within 1 %
  // of the exact force at degree 12 (338 nodes per sphere), where the point-dipole model
  // (mutually induced dipoles at the centres) is off by a factor of 4.8; along the grid's pole
  // and along another axis
  const double eps = 10, beta = (eps - 1) / (eps + 2);
  const double ref = kifmm_points::two_sphere_force(1, 2, eps, 1, 400);
  EXPECT_NEAR(ref / kifmm_points::two_sphere_force(1, 2, eps, 1, 300), 1.0, 1e-6);    // converged
  for (const double *axis : {(const double[3]){0, 0, 1}, (const double[3]){0.48, 0.6, 0.64}}) {
    const double f = bie_force(nullptr, 1, 2, eps, axis, 12);
    EXPECT_LT(std::fabs(f / ref - 1), 1e-2) << f << " against " << ref;
  }
  const double p = 4 * kPi * beta / (1 - beta / 4), dipole_model = -6 * p * p / (4 * kPi * 16);
  EXPECT_GT(ref / dipole_model, 4.0);
  // without the grid drawn towards the contact the same degree is off by 25 %
  EXPECT_GT(std::fabs(bie_force(nullptr, 1, 2, eps, (const double[3]){0, 0, 1}, 12, nullptr, 1.0) / ref - 1), 0.1);
}

TEST(DielectricSpheres, NearlyTouchingSpheresMatchTheReference)
{
  // gaps of 0.05 and 0.01 radii at degree 12
  const double axis[3] = {0, 0.6, 0.8};
  for (double d : {2.05, 2.01}) {
    const double ref = kifmm_points::two_sphere_force(1, d, 10, 1, 400), f = bie_force(nullptr, 1, d, 10, axis, 12);
    EXPECT_LT(std::fabs(f / ref - 1), 1e-3) << "d " << d << ": " << f << " against " << ref;
  }
}

TEST(DielectricSpheres, FmmEqualsDirectSum)
{
  // a bent chain of six spheres of two sizes and permittivities, nearly touching, field at an angle
  const double c[18] = {0, 0, 0, 2.05, 0, 0, 3.6, 1.3, 0, 3.7, 3.2, 0.4, 5.3, 4.0, 1.2, 7.3, 4.3, 1.5};
  const double r[6] = {1, 1, 0.8, 1, 0.9, 1}, eps[6] = {10, 10, 4, 10, 6, 10}, E[3] = {0.6, 0.3, -0.2};
  kifmm::DielectricSphereOptions opt;
  opt.degree = 8;
  opt.tolerance = 1e-10;
  const auto direct = kifmm::polarize_dielectric_spheres(nullptr, 6, c, r, eps, E, opt);
  kifmm::Options o;
  o.order = 10;
  auto ev = kifmm::make_evaluator(kifmm::KernelSpec{}, o);
  const auto fmm = kifmm::polarize_dielectric_spheres(ev.get(), 6, c, r, eps, E, opt);
  ASSERT_TRUE(direct.converged && fmm.converged);
  EXPECT_GT(direct.near_rows, 0u);
  double fmax = 0, worst = 0;
  for (int k = 0; k < 18; ++k) fmax = std::max(fmax, std::fabs(direct.force[k]));
  for (int k = 0; k < 18; ++k) worst = std::max(worst, std::fabs(fmm.force[k] - direct.force[k]));
  EXPECT_LT(worst, 1e-6 * fmax);
}

TEST(DielectricSpheres, BadInputIsAnError)
{
  const double c[6] = {0, 0, 0, 1.9, 0, 0}, r[2] = {1, 1}, eps[2] = {10, 10}, E[3] = {1, 0, 0};
  kifmm::DielectricSphereOptions opt;
  opt.degree = 4;
  EXPECT_THROW(kifmm::polarize_dielectric_spheres(nullptr, 2, c, r, eps, E, opt), std::invalid_argument);    // overlap
  const double c2[6] = {0, 0, 0, 3, 0, 0}, r0[2] = {1, 0}, eps0[2] = {10, -1};
  EXPECT_THROW(kifmm::polarize_dielectric_spheres(nullptr, 2, c2, r0, eps, E, opt), std::invalid_argument);
  EXPECT_THROW(kifmm::polarize_dielectric_spheres(nullptr, 2, c2, r, eps0, E, opt), std::invalid_argument);
  kifmm::KernelSpec yukawa{kifmm::KernelType::Yukawa, 1.0};
  auto ev = kifmm::make_evaluator(yukawa, kifmm::Options{});
  EXPECT_THROW(kifmm::polarize_dielectric_spheres(ev.get(), 2, c2, r, eps, E, opt), std::invalid_argument);
  opt.degree = 0;
  EXPECT_THROW(kifmm::polarize_dielectric_spheres(nullptr, 2, c2, r, eps, E, opt), std::invalid_argument);
}

TEST(DielectricSpheres, ChainOfThreeMatchesTheReference)
{
  // three spheres in a row along the field, gaps of 0.1 radii: the middle one has two close
  // neighbours (undrawn grid); the end forces against the axial multipole solution of three
  // spheres (which reduces to the two-sphere one), the middle force zero by symmetry
  EXPECT_NEAR(kifmm_points::axial_spheres_forces({1.05, -1.05}, {1, 1}, {10, 10}, 1, 100)[0] /
                  kifmm_points::two_sphere_force(1, 2.1, 10, 1, 100), 1.0, 1e-12);
  const double d = 2.1;
  const auto ref = kifmm_points::axial_spheres_forces({d, 0, -d}, {1, 1, 1}, {10, 10, 10}, 1, 200);
  const double c[9] = {0, 0, d, 0, 0, 0, 0, 0, -d}, r[3] = {1, 1, 1}, e[3] = {10, 10, 10}, E[3] = {0, 0, 1};
  kifmm::DielectricSphereOptions o;
  o.degree = 12;
  o.tolerance = 1e-11;
  const auto s = kifmm::polarize_dielectric_spheres(nullptr, 3, c, r, e, E, o);
  EXPECT_LT(std::fabs(s.force[2] / ref[0] - 1), 1e-2) << s.force[2] << " against " << ref[0];
  EXPECT_LT(std::fabs(s.force[8] / ref[2] - 1), 1e-2) << s.force[8] << " against " << ref[2];
  EXPECT_LT(std::fabs(s.force[5]), 1e-8 * std::fabs(ref[0]));
}

TEST(DielectricSpheres, OverlapsSolvedAsTouching)
{
  // three spheres, two of them overlapping by 0.2 radii, the third clear: touch_overlaps takes
  // 0.1 off both radii of the pair and solves the touching spheres; the third keeps its radius
  const double c[9] = {0, 0, 0, 1.8, 0, 0, 0, 3, 0}, r[3] = {1, 1, 1}, eps[3] = {10, 10, 10}, E[3] = {1, 0.5, 0};
  kifmm::DielectricSphereOptions opt;
  opt.degree = 8;
  opt.touch_overlaps = true;
  const auto s = kifmm::polarize_dielectric_spheres(nullptr, 3, c, r, eps, E, opt);
  EXPECT_EQ(s.overlapping_pairs, 1u);
  EXPECT_NEAR(s.radius[0], 0.9, 1e-8);
  EXPECT_NEAR(s.radius[1], 0.9, 1e-8);
  EXPECT_EQ(s.radius[2], 1.0);
  opt.touch_overlaps = false;
  const auto t = kifmm::polarize_dielectric_spheres(nullptr, 3, c, s.radius.data(), eps, E, opt);
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(s.force[k], t.force[k], 1e-9);
  // a sphere (nearly) inside another is an error either way
  const double c2[6] = {0, 0, 0, 0.05, 0, 0};
  opt.touch_overlaps = true;
  EXPECT_THROW(kifmm::polarize_dielectric_spheres(nullptr, 2, c2, r, eps, E, opt), std::invalid_argument);
}
