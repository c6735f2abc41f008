// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Union-of-spheres mass properties (no LAMMPS): single sphere, two overlapping spheres against
// the exact lens / solid-of-revolution formulas, disjoint and nested spheres, rotation
// invariance, duplicate detection; the small linear algebra of fix clump/rigid.
#include "clump_math.h"
#include "clump_template.h"
#include "clump_union.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

using namespace clump;

namespace {

// Exact mass properties of the union of the balls (centre 0, radius R) and (centre d e_z,
// radius r), |R - r| < d < R + r, density rho: the union is a solid of revolution whose
// section radius^2 is R^2 - z^2 below the plane of the intersection circle and
// r^2 - (z - d)^2 above it. Integrals of polynomials of degree <= 4 per piece, done exactly
// by 5-point Gauss-Legendre.
struct Exact {
  double mass, zc, ixx, izz;    // inertia about the COM: ixx = iyy (transverse), izz (axial)
};

Exact exact_two_spheres(double R, double r, double d, double rho)
{
  const double zs = (d * d + R * R - r * r) / (2 * d);
  const double gx[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                        0.9061798459386640};
  const double gw[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                        0.4786286704993665, 0.2369268850561891};
  double v = 0, mz = 0, z2 = 0, r4 = 0;
  auto piece = [&](double a, double b, auto sec2) {
    for (int k = 0; k < 5; ++k) {
      double z = 0.5 * (a + b) + 0.5 * (b - a) * gx[k], w = 0.5 * (b - a) * gw[k];
      double s = sec2(z);
      v += w * M_PI * s;
      mz += w * M_PI * z * s;
      z2 += w * M_PI * z * z * s;
      r4 += w * s * s;
    }
  };
  piece(-R, zs, [&](double z) { return R * R - z * z; });
  piece(zs, d + r, [&](double z) { return r * r - (z - d) * (z - d); });
  Exact e;
  e.mass = rho * v;
  e.zc = mz / v;
  e.izz = rho * M_PI / 2 * r4;                          // disks: (1/2) m s^2
  e.ixx = rho * (M_PI / 4 * r4 + z2) - e.mass * e.zc * e.zc;    // (1/4) m s^2 + m z^2
  return e;
}

// Standard lens (sphere-sphere intersection) volume
double lens_volume(double R, double r, double d)
{
  return M_PI * std::pow(R + r - d, 2) *
      (d * d + 2 * d * r - 3 * r * r + 2 * d * R + 6 * r * R - 3 * R * R) / (12 * d);
}

Mat3 rotation(double ax, double ay, double az)
{
  Mat3 rx{{{1, 0, 0}, {0, std::cos(ax), -std::sin(ax)}, {0, std::sin(ax), std::cos(ax)}}};
  Mat3 ry{{{std::cos(ay), 0, std::sin(ay)}, {0, 1, 0}, {-std::sin(ay), 0, std::cos(ay)}}};
  Mat3 rz{{{std::cos(az), -std::sin(az), 0}, {std::sin(az), std::cos(az), 0}, {0, 0, 1}}};
  return matmul(rz, matmul(ry, rx));
}

Mat3 tensor(const MassProperties &p)
{
  return {{{p.itensor[0], p.itensor[5], p.itensor[4]},
           {p.itensor[5], p.itensor[1], p.itensor[3]},
           {p.itensor[4], p.itensor[3], p.itensor[2]}}};
}

}    // namespace

TEST(ClumpUnion, SingleSphereIsExact)
{
  const double r = 0.3, rho = 2500.0;
  MassProperties p = union_mass_properties({{{1.0, -2.0, 0.5}, r}}, rho, 1e-10);
  const double m = rho * 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(p.mass / m, 1.0, 1e-10);
  EXPECT_NEAR(p.com[0], 1.0, 1e-12);
  EXPECT_NEAR(p.com[1], -2.0, 1e-12);
  EXPECT_NEAR(p.com[2], 0.5, 1e-12);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(p.itensor[k] / (0.4 * m * r * r), 1.0, 1e-10);
  for (int k = 3; k < 6; ++k) EXPECT_NEAR(p.itensor[k] / (0.4 * m * r * r), 0.0, 1e-12);
  EXPECT_LE(p.rel_error, 1e-10);
}

// Two overlapping spheres against the exact formulas, at the default tolerance (1e-5) and a
// tight one (1e-8), for several radii and distances, axis-aligned and rotated: the actual
// error must be below the requested tolerance and below the reported estimate.
TEST(ClumpUnion, TwoOverlappingSpheresMatchLensFormula)
{
  struct Case {
    double R, r, d;
  };
  const double rho = 1.7;
  for (Case c : {Case{1.0, 1.0, 0.3}, Case{1.0, 1.0, 1.1}, Case{1.0, 0.7, 1.1},
                 Case{1.0, 0.7, 1.6}, Case{0.008, 0.008, 0.01}}) {
    Exact e = exact_two_spheres(c.R, c.r, c.d, rho);
    // the union volume is the two balls minus the lens
    const double vunion =
        4.0 / 3.0 * M_PI * (c.R * c.R * c.R + c.r * c.r * c.r) - lens_volume(c.R, c.r, c.d);
    ASSERT_NEAR(e.mass / (rho * vunion), 1.0, 1e-13);
    for (double tol : {1e-5, 1e-8})
      for (int rotated = 0; rotated < 2; ++rotated) {
        SCOPED_TRACE(testing::Message() << "R=" << c.R << " r=" << c.r << " d=" << c.d
                                        << " tol=" << tol << " rotated=" << rotated);
        Mat3 rot = rotated ? rotation(0.3, -1.1, 2.0) : rotation(0, 0, 0);
        Vec3 shift = {0.2 * c.R, -0.7 * c.R, 0.1 * c.R};
        Vec3 a = matvec(rot, {0, 0, 0}), b = matvec(rot, {0, 0, c.d});
        std::vector<Sphere> s = {{{a[0] + shift[0], a[1] + shift[1], a[2] + shift[2]}, c.R},
                                 {{b[0] + shift[0], b[1] + shift[1], b[2] + shift[2]}, c.r}};
        MassProperties p = union_mass_properties(s, rho, tol);
        const double err_m = std::fabs(p.mass / e.mass - 1.0);
        EXPECT_LT(err_m, tol);
        EXPECT_LE(err_m, p.rel_error);
        EXPECT_LE(p.rel_error, 1.01 * tol);    // the estimate meets the request
        Vec3 zc = matvec(rot, {0, 0, e.zc});
        for (int d = 0; d < 3; ++d) EXPECT_NEAR(p.com[d], zc[d] + shift[d], tol * c.R);
        // inertia: R diag(ixx, ixx, izz) R^T
        Mat3 want = matmul(matmul(rot, Mat3{{{e.ixx, 0, 0}, {0, e.ixx, 0}, {0, 0, e.izz}}}),
                           transpose(rot));
        Mat3 got = tensor(p);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) EXPECT_NEAR(got[i][j], want[i][j], tol * e.izz);
      }
  }
}

TEST(ClumpUnion, DisjointSpheresAddUpAndNestedSphereAddsNothing)
{
  const double rho = 3.0;
  // two disjoint balls (touching at one point)
  MassProperties p = union_mass_properties({{{0, 0, 0}, 0.5}, {{1.0, 0, 0}, 0.5}}, rho, 1e-9);
  const double m1 = rho * 4.0 / 3.0 * M_PI * 0.125;
  EXPECT_NEAR(p.mass / (2 * m1), 1.0, 1e-9);
  EXPECT_NEAR(p.com[0], 0.5, 1e-9);
  EXPECT_NEAR(p.itensor[0] / (2 * 0.4 * m1 * 0.25), 1.0, 1e-9);                   // Ixx
  EXPECT_NEAR(p.itensor[1] / (2 * (0.4 * m1 * 0.25 + m1 * 0.25)), 1.0, 1e-9);    // Iyy
  // a ball inside another adds nothing; a concentric copy of smaller radius neither
  MassProperties q = union_mass_properties(
      {{{0, 0, 0}, 1.0}, {{0.3, 0.2, -0.1}, 0.4}, {{0, 0, 0}, 0.5}}, rho, 1e-9);
  EXPECT_NEAR(q.mass / (rho * 4.0 / 3.0 * M_PI), 1.0, 1e-9);
  EXPECT_NEAR(q.com[0], 0.0, 1e-9);
}

TEST(ClumpUnion, RotatedCopyHasRotatedTensorAndSameMass)
{
  // an asymmetric 5-pebble clump with overlaps and different radii
  std::vector<Sphere> s = {{{0, 0, 0}, 0.6},
                           {{0.7, 0.1, 0}, 0.5},
                           {{-0.5, 0.4, 0.2}, 0.45},
                           {{0.2, -0.6, 0.3}, 0.4},
                           {{1.2, 0.3, -0.2}, 0.3}};
  MassProperties p = union_mass_properties(s, 1.0, 1e-7);
  Mat3 rot = rotation(0.7, 0.2, -1.3);
  std::vector<Sphere> t = s;
  for (auto &sp : t) {
    Vec3 x = matvec(rot, {sp.x[0], sp.x[1], sp.x[2]});
    for (int d = 0; d < 3; ++d) sp.x[d] = x[d] + 5.0;
  }
  MassProperties q = union_mass_properties(t, 1.0, 1e-7);
  EXPECT_NEAR(q.mass / p.mass, 1.0, 2e-7);
  Vec3 c = matvec(rot, {p.com[0], p.com[1], p.com[2]});
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(q.com[d], c[d] + 5.0, 1e-6);
  Mat3 want = matmul(matmul(rot, tensor(p)), transpose(rot)), got = tensor(q);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(got[i][j], want[i][j], 2e-7 * p.itensor[0]);
  // overlaps remove mass: less than the sum of the balls
  double sum = 0;
  for (auto &sp : s) sum += 4.0 / 3.0 * M_PI * sp.r * sp.r * sp.r;
  EXPECT_LT(p.mass, 0.9 * sum);
}

TEST(ClumpUnion, DuplicatePebblesAreFound)
{
  std::vector<Sphere> s = {{{0, 0, 0}, 1.0}, {{1, 0, 0}, 1.0}, {{0, 0, 1e-9}, 0.5}};
  auto d = duplicate_spheres(s);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0][0], 0);
  EXPECT_EQ(d[0][1], 2);
  EXPECT_TRUE(duplicate_spheres({{{0, 0, 0}, 1.0}, {{0.01, 0, 0}, 1.0}}).empty());
}

// Regression tests of the fuzz target fuzz/fuzz_clump_template.cpp (inputs in
// fuzz/corpus/clump_template/crash-* and regression-*): before check_pebbles, a coordinate
// that overflows to +-inf (e.g. "1e400", which LAMMPS's molecule reader accepts), or
// coordinates around 1e300, made the duplicate search convert an out-of-range double to long
// (UBSan: "-inf is outside the range of representable values of type 'long'"). Every such
// template is now refused with a message naming the pebble. Radii outside [1e-60, 1e60] too
// (their volume or moments of inertia overflow or underflow).
TEST(ClumpTemplate, FuzzFindingsAreClearErrors)
{
  using clump::check_pebbles;
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<clump::Sphere> dimer = {{{-0.003, 0, 0}, 0.005}, {{0.003, 0, 0}, 0.005}};
  EXPECT_EQ(check_pebbles(dimer), "");

  auto s = dimer;
  s[1].x[1] = -inf;    // crash-430ac97c: "-0.01011e3087108" overflows to -inf
  EXPECT_EQ(check_pebbles(s), "pebble 2 has a non-finite coordinate (0.003, -inf, 0)");
  s = dimer;
  s[0].x[2] = nan;
  EXPECT_EQ(check_pebbles(s, {11, 12}), "pebble 11 has a non-finite coordinate (-0.003, 0, nan)");
  s = dimer;
  s[0].x[0] = 1e300;    // regression-huge-coordinates
  s[1].x[0] = -1e300;
  EXPECT_EQ(check_pebbles(s), "pebble 2 is farther than 1e+09 largest radii from pebble 1 (not a clump)");
  s = dimer;    // far from the origin but a fine clump: no overflow in the duplicate search
  s[0].x[0] = 1e300;
  s[1].x[0] = 1e300;
  s[1].x[1] = 0.006;
  EXPECT_EQ(check_pebbles(s), "");
  s[1].x[1] = 0.0;
  EXPECT_EQ(check_pebbles(s).rfind("1 pair(s) of duplicate (coincident) pebbles, first: pebbles 1 and 2", 0), 0u);
  s = dimer;
  s[1].r = inf;
  EXPECT_EQ(check_pebbles(s), "pebble 2 has diameter inf (must be finite and > 0)");
  s[1].r = 0.0;
  EXPECT_EQ(check_pebbles(s), "pebble 2 has diameter 0 (must be finite and > 0)");
  s[1].r = nan;
  EXPECT_EQ(check_pebbles(s), "pebble 2 has diameter nan (must be finite and > 0)");
  s[1].r = 5e-303;    // regression-radius-ratio: now outside the representable range
  EXPECT_EQ(check_pebbles(s), "pebble 2 has diameter 1e-302 (must be between 2e-60 and 2e60: its moments of "
                              "inertia would not fit a double)");
  s[1].r = 1e-9;
  EXPECT_EQ(check_pebbles(s), "pebble diameters from 2e-09 to 0.01: a ratio above 1e+06 is not supported");
  // regression-huge-radius (found by fuzzing): one pebble of radius 5e299 passed the
  // checks and its volume overflowed to inf in union_mass_properties
  EXPECT_EQ(check_pebbles({{{0, 0, 0}, 5e299}}), "pebble 1 has diameter 1e+300 (must be between 2e-60 and 2e60: its "
                                                  "moments of inertia would not fit a double)");
  EXPECT_EQ(check_pebbles({}), "no pebbles");
}

TEST(ClumpMath, BestRotationRecoversRotation)
{
  Mat3 rot = rotation(0.4, -0.9, 2.5);
  std::vector<Vec3> p = {{1, 0, 0}, {0, 2, 0}, {0, 0, 3}, {-1, -2, -3}}, q;
  for (auto &x : p) q.push_back(matvec(rot, x));
  double rms;
  Mat3 r = best_rotation(p, q, rms);
  EXPECT_LT(rms, 1e-12);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(r[i][j], rot[i][j], 1e-12);
  // a mirror image is not a rotation: large residual
  std::vector<Vec3> m;
  for (auto &x : p) m.push_back({-x[0], x[1], x[2]});
  best_rotation(p, m, rms);
  EXPECT_GT(rms, 0.1);
}

TEST(ClumpMath, RigidMotionFit)
{
  std::vector<Vec3> x = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.3, 0.2, 1}};
  Vec3 w = {0.3, -1.2, 0.5}, v0 = {1, 2, 3}, c = {0.2, 0.1, 0.4};
  std::vector<Vec3> v;
  for (auto &p : x) {
    Vec3 r = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    v.push_back({v0[0] + w[1] * r[2] - w[2] * r[1], v0[1] + w[2] * r[0] - w[0] * r[2],
                 v0[2] + w[0] * r[1] - w[1] * r[0]});
  }
  Vec3 vc, om;
  fit_rigid_motion(x, v, c, vc, om);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(vc[d], v0[d], 1e-12);
    EXPECT_NEAR(om[d], w[d], 1e-12);
  }
  // collinear points: the spin about the line is undetermined and set to zero
  std::vector<Vec3> xl = {{-1, 0, 0}, {0, 0, 0}, {1, 0, 0}};
  std::vector<Vec3> vl = {{0, -2, 0}, {0, 0, 0}, {0, 2, 0}};    // omega = 2 e_z
  fit_rigid_motion(xl, vl, {0, 0, 0}, vc, om);
  EXPECT_NEAR(om[0], 0.0, 1e-12);
  EXPECT_NEAR(om[2], 2.0, 1e-12);
}
