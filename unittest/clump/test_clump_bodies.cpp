// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Rigid-body data of clumps without LAMMPS (clump_bodies.h): rotated copies of a shape reuse
// its integration and equal a fresh integration of the rotated pebbles, a mirror image is not
// taken for a rotation, rigid motion gives back the centre-of-mass velocity and I omega,
// pebble order does not matter, bad pebbles name the clump, the file text parses back.
#include "clump_bodies.h"
#include "clump_union.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

using namespace clump;

namespace {

constexpr double density = 2.0, tol = 1e-7;

// an asymmetric (chiral) clump of 4 overlapping pebbles of two radii
std::vector<Pebble> chiral(long id, long tag0, const Mat3 &rot, const Vec3 &shift, bool mirror = false)
{
  const double c[4][3] = {{0, 0, 0}, {0.8, 0, 0}, {0.1, 0.7, 0}, {0.2, 0.1, 0.6}};
  const double r[4] = {0.5, 0.4, 0.45, 0.35};
  std::vector<Pebble> out;
  for (int k = 0; k < 4; ++k) {
    Vec3 p{c[k][0], c[k][1], mirror ? -c[k][2] : c[k][2]};
    const Vec3 q = matvec(rot, p);
    out.push_back({id, tag0 + k, {q[0] + shift[0], q[1] + shift[1], q[2] + shift[2]}, {0, 0, 0}, r[k]});
  }
  return out;
}

Mat3 rotation(double angle, Vec3 axis)
{
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  for (double &a : axis) a /= n;
  const double c = std::cos(angle / 2), s = std::sin(angle / 2);
  return quat_to_matrix({c, s * axis[0], s * axis[1], s * axis[2]});
}

MassProperties fresh(const std::vector<Pebble> &p)
{
  std::vector<Sphere> s;
  for (const Pebble &q : p) s.push_back({{q.x[0], q.x[1], q.x[2]}, q.r});
  return union_mass_properties(s, density, tol);
}

}    // namespace

TEST(ClumpBodies, RotatedCopyReusesTheShapeAndEqualsAFreshIntegration)
{
  const Mat3 id = rotation(0.0, {0, 0, 1}), rot = rotation(1.1, {1, 2, -0.5});
  auto a = chiral(7, 1, id, {0, 0, 0});
  auto b = chiral(3, 5, rot, {4.0, -2.0, 1.5});
  std::vector<Pebble> all = a;
  all.insert(all.end(), b.begin(), b.end());
  const BodiesResult r = compute_bodies(all, density, tol);
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_EQ(r.bodies.size(), 2u);
  EXPECT_EQ(r.shapes_integrated, 1);
  EXPECT_EQ(r.bodies[0].id, 3);    // sorted by clump ID
  EXPECT_EQ(r.bodies[1].id, 7);
  const MassProperties pb = fresh(b);
  const Body &body = r.bodies[0];
  EXPECT_NEAR(body.mass, pb.mass, 1e-6 * pb.mass);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(body.com[d], pb.com[d], 1e-6);
  const double scale = std::max({pb.itensor[0], pb.itensor[1], pb.itensor[2]});
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(body.itensor[k], pb.itensor[k], 1e-5 * scale) << k;
  EXPECT_GT(r.worst_rel_error, 0.0);
  EXPECT_LT(r.worst_rel_error, 10 * tol);
}

TEST(ClumpBodies, MirrorImageIsIntegratedOnItsOwn)
{
  const Mat3 id = rotation(0.0, {0, 0, 1});
  auto a = chiral(1, 1, id, {0, 0, 0});
  auto m = chiral(2, 5, id, {3, 0, 0}, true);
  std::vector<Pebble> all = a;
  all.insert(all.end(), m.begin(), m.end());
  const BodiesResult r = compute_bodies(all, density, tol);
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_EQ(r.shapes_integrated, 2);
  const MassProperties pm = fresh(m);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(r.bodies[1].com[d], pm.com[d], 1e-6);
  EXPECT_NEAR(r.bodies[1].itensor[3], pm.itensor[3], 1e-6);    // yz flips sign with z
}

TEST(ClumpBodies, RigidMotionGivesCentreVelocityAndAngularMomentum)
{
  auto p = chiral(1, 1, rotation(0.4, {0, 1, 1}), {1, 1, 1});
  const BodiesResult r0 = compute_bodies(p, density, tol);
  ASSERT_TRUE(r0.error.empty());
  const Body &b0 = r0.bodies[0];
  const Vec3 vc{0.3, -0.2, 0.1}, w{0.5, 1.5, -0.7};
  for (Pebble &q : p) {
    const Vec3 a{q.x[0] - b0.com[0], q.x[1] - b0.com[1], q.x[2] - b0.com[2]};
    q.v = {vc[0] + w[1] * a[2] - w[2] * a[1], vc[1] + w[2] * a[0] - w[0] * a[2],
           vc[2] + w[0] * a[1] - w[1] * a[0]};
  }
  const Body b = compute_bodies(p, density, tol).bodies[0];
  const Vec3 l = matvec(itensor_to_matrix(b.itensor), w);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(b.vcm[d], vc[d], 1e-12);
    EXPECT_NEAR(b.angmom[d], l[d], 1e-12 * std::fabs(l[d]) + 1e-14);
  }
}

TEST(ClumpBodies, PebbleOrderDoesNotMatter)
{
  std::vector<Pebble> all;
  for (long c = 1; c <= 5; ++c) {
    auto p = chiral(c, 10 * c, rotation(0.3 * c, {1, 0, (double) c}), {2.0 * c, 0, 0});
    all.insert(all.end(), p.begin(), p.end());
  }
  const BodiesResult r = compute_bodies(all, density, tol);
  std::mt19937 g(3);
  std::shuffle(all.begin(), all.end(), g);
  const BodiesResult s = compute_bodies(all, density, tol);
  EXPECT_EQ(r.shapes_integrated, 1);
  EXPECT_EQ(bodies_file_text(r.bodies, "c", density), bodies_file_text(s.bodies, "c", density));
}

TEST(ClumpBodies, DuplicatePebblesNameTheClump)
{
  auto p = chiral(42, 100, rotation(0.0, {0, 0, 1}), {0, 0, 0});
  p.push_back(p[1]);
  p.back().tag = 200;
  const BodiesResult r = compute_bodies(p, density, tol);
  EXPECT_TRUE(r.bodies.empty());
  EXPECT_NE(r.error.find("clump (molecule ID) 42"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("101 and 200"), std::string::npos) << r.error;
}

TEST(ClumpBodies, FileTextParsesBack)
{
  auto p = chiral(9, 1, rotation(0.7, {1, 1, 0}), {0.5, 0.25, 0});
  const BodiesResult r = compute_bodies(p, density, tol);
  std::istringstream in(bodies_file_text(r.bodies, "pile", density));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "# fix clump/rigid pile: union-of-spheres mass properties at density 2");
  std::getline(in, line);
  EXPECT_EQ(line.rfind("# id mass xcm", 0), 0u);
  int n = 0;
  in >> n;
  ASSERT_EQ(n, 1);
  std::vector<double> v(20);
  for (double &x : v) in >> x;
  ASSERT_TRUE((bool) in);
  const Body &b = r.bodies[0];
  EXPECT_EQ(v[0], 9);
  EXPECT_EQ(v[1], b.mass);    // 17 digits: exact
  EXPECT_EQ(v[2], b.com[0]);
  EXPECT_EQ(v[8], b.itensor[5]);    // ixy after izz (infile order: xx yy zz xy xz yz)
  EXPECT_EQ(v[10], b.itensor[3]);
  EXPECT_EQ(v[17], 0.0);
}
