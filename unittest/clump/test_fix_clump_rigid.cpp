// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix clump/rigid through the in-process LAMMPS fixture: union masses of created, deposited
// and read clumps, the masses the granular pair and wall styles use, intra-clump exclusion,
// initial motion, torque-free rotation (energy, angular momentum, intermediate axis), a dipole
// clump in a uniform field, a charged clump's acceleration, bounces off a granular wall, errors.
#include "clump_test_util.h"
#include "lammps_fixture.h"

#include "clump_math.h"
#include "clump_union.h"

#include "atom.h"
#include "input.h"
#include "fix.h"
#include "force.h"
#include "lammps.h"
#include "modify.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

using namespace clump_test;
using kifmm_test::LammpsFixture;
using LAMMPS_NS::Fix;

namespace {

const double RHO = 2500.0;

// reference union mass properties, requested to 1e-7 (1e-6 for the larger shapes; actual
// errors are 10-100x smaller), once per shape
const clump::MassProperties &reference(const std::vector<Pebble> &p)
{
  static std::map<std::vector<double>, clump::MassProperties> cache;
  std::vector<double> key;
  for (const auto &q : p) key.insert(key.end(), {q.x, q.y, q.z, q.r});
  auto it = cache.find(key);
  if (it == cache.end())
    it = cache.emplace(key, clump::union_mass_properties(spheres(p), RHO, p.size() > 10 ? 1e-6 : 1e-7))
             .first;
  return it->second;
}

double union_mass(const std::vector<Pebble> &p)
{
  return reference(p).mass;
}

std::array<double, 3> principal_moments(const std::vector<Pebble> &p)
{
  const auto &m = reference(p);
  double a[9] = {m.itensor[0], m.itensor[5], m.itensor[4], m.itensor[5], m.itensor[1],
                 m.itensor[3], m.itensor[4], m.itensor[3], m.itensor[2]};
  double ev[3], evec[9];
  clump::jacobi_symmetric(3, a, ev, evec);
  std::array<double, 3> out = {ev[0], ev[1], ev[2]};
  std::sort(out.begin(), out.end());
  return out;
}

class FixClumpRigidTest : public LammpsFixture {
 protected:
  std::string dimer_file, asym_file;
  void SetUp() override
  {
    LammpsFixture::SetUp();
    dimer_file = write_molecule("dimer", dimer());
    asym_file = write_molecule("asym", asymmetric());
  }
  std::map<int, std::vector<double>> rows(const std::string &fix = "c")
  {
    return clump_rows(lmp, fix);
  }
  Fix *fix(const std::string &id)
  {
    int i = lmp->modify->find_fix(id);
    return i >= 0 ? lmp->modify->fix[i] : nullptr;
  }
};

}    // namespace

TEST_F(FixClumpRigidTest, CreatedClumpsHaveUnionMassAndInertia)
{
  commands(box_commands());
  commands("molecule dip " + potentials + "/dipole3.mol\n" + "molecule dim " + dimer_file +
           "\nmolecule plt " + potentials + "/platelet_n3.mol\n" + R"(
create_atoms 0 single 0 0 0 mol dip 11
create_atoms 0 single 0.05 0 0 mol dim 12
create_atoms 0 single -0.08 0.02 0 mol plt 13
pair_style zero 0.02
pair_coeff * *
fix c all clump/rigid density 2500
run 0
)");
  EXPECT_EQ(evaluate("f_c[1]"), 3.0);
  auto r = rows();
  ASSERT_EQ(r.size(), 3u);
  auto dip = read_molecule(potentials + "/dipole3.mol");
  auto plt = read_molecule(potentials + "/platelet_n3.mol");
  ASSERT_EQ(dip.size(), 3u);
  ASSERT_EQ(plt.size(), 38u);
  // dipole3: touching pebbles, union = sum of the balls
  const double mdip = 3 * RHO * 4.0 / 3.0 * M_PI * std::pow(0.005, 3);
  EXPECT_NEAR(r[1][MASS] / mdip, 1.0, 1e-5);
  EXPECT_NEAR(r[2][MASS] / union_mass(dimer()), 1.0, 2e-5);
  EXPECT_NEAR(r[3][MASS] / union_mass(plt), 1.0, 2e-5);
  // overlaps remove mass: the union is lighter than the balls
  EXPECT_LT(r[2][MASS], 0.95 * 2 * RHO * 4.0 / 3.0 * M_PI * std::pow(0.005, 3));
  const std::vector<Pebble> *shapes[3] = {&dip, nullptr, &plt};
  auto dim = dimer();
  shapes[1] = &dim;
  for (int m = 1; m <= 3; ++m) {
    auto want = principal_moments(*shapes[m - 1]);
    std::array<double, 3> got = {r[m][INERTIAX], r[m][INERTIAY], r[m][INERTIAZ]};
    std::sort(got.begin(), got.end());
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k] / want[2], want[k] / want[2], 2e-5) << m;
  }
  EXPECT_NEAR(evaluate("f_c[2]"), 0.0, 1e-30);
  EXPECT_NEAR(evaluate("f_c[3]"), 0.0, 1e-30);
}

// Granular pair and wall styles take the first fix with rigid_flag and use
// extract("masstotal")[extract("body")[i]] as the mass of atom i: that must be the clump.
TEST_F(FixClumpRigidTest, RigidFixSeenByGranularStylesHasClumpMasses)
{
  commands(box_commands());
  commands("molecule dim " + dimer_file + "\nmolecule asym " + asym_file + R"(
create_atoms 0 single 0 0 0 mol dim 12
create_atoms 0 single 0.05 0 0 mol asym 13
pair_style zero 0.02
pair_coeff * *
fix c all clump/rigid density 2500
run 0
)");
  Fix *first_rigid = nullptr;
  for (int i = 0; i < lmp->modify->nfix; ++i)
    if (lmp->modify->fix[i]->rigid_flag) {
      first_rigid = lmp->modify->fix[i];
      break;
    }
  ASSERT_NE(first_rigid, nullptr);
  EXPECT_STREQ(first_rigid->id, "c_rigid");
  EXPECT_EQ(fix("c")->rigid_flag, 0);
  int dim;
  int *body = (int *) first_rigid->extract("body", dim);
  double *mass = (double *) first_rigid->extract("masstotal", dim);
  ASSERT_NE(body, nullptr);
  ASSERT_NE(mass, nullptr);
  const double want[3] = {0.0, union_mass(dimer()), union_mass(asymmetric())};
  auto *atom = lmp->atom;
  for (int i = 0; i < atom->nlocal; ++i) {
    ASSERT_GE(body[i], 0);
    EXPECT_NEAR(mass[body[i]] / want[atom->molecule[i]], 1.0, 2e-5) << "atom " << atom->tag[i];
  }
}

// Two dimers approach head on and touch with one pebble pair; gran/hooke with kn = 0 gives
// the pure damping force meff * gamman * vn with meff = M1 M2 / (M1 + M2) = M / 2.
TEST_F(FixClumpRigidTest, PairDampingUsesClumpMass)
{
  commands(box_commands());
  commands("molecule dim " + dimer_file + R"(
create_atoms 0 single -0.00795 0 0 mol dim 12 rotate 0 0 0 1
create_atoms 0 single 0.00795 0 0 mol dim 13 rotate 0 0 0 1
pair_style gran/hooke 0.0 0.0 100.0 0.0 0.0 0
pair_coeff * *
velocity all set 0.05 0 0
group b molecule 2
velocity b set -0.05 0 0
fix c all clump/rigid density 2500
run 0
)");
  auto r = rows();
  const double m = r[1][MASS];    // the clump mass rigid/small has
  EXPECT_NEAR(m / union_mass(dimer()), 1.0, 2e-5);
  EXPECT_EQ(r[2][MASS], m);
  auto f = forces_by_id();
  ASSERT_EQ(f.size(), 4u);
  // pebble 2 (right of clump 1) touches pebble 3 (left of clump 2); vn = 0.1
  const double want = 0.5 * m * 100.0 * 0.1;
  EXPECT_NEAR(f[2][0] / want, -1.0, 1e-9);
  EXPECT_NEAR(f[3][0] / want, 1.0, 1e-9);
  EXPECT_NEAR(f[1][0], 0.0, 1e-15);
  EXPECT_NEAR(f[4][0], 0.0, 1e-15);
  // the clump force is the pebble force
  EXPECT_NEAR(r[1][FX] / want, -1.0, 1e-9);
}

// Pebbles of one clump overlap, but never interact (default exclude yes); with exclude no
// the pair style pushes them apart (internal forces, cancelling in the clump's sum).
TEST_F(FixClumpRigidTest, NoContactsInsideAClump)
{
  for (const char *exclude : {"yes", "no"}) {
    create();
    commands(box_commands());
    commands("molecule dim " + dimer_file + R"(
create_atoms 0 single 0 0 0 mol dim 12 rotate 0 0 0 1
pair_style gran/hooke 1000.0 0.0 0.0 0.0 0.0 0
pair_coeff * *
)");
    command(std::string("fix c all clump/rigid density 2500 exclude ") + exclude);
    command("run 0");
    auto f = forces_by_id();
    if (std::string(exclude) == "yes") {
      EXPECT_EQ(f[1][0], 0.0);
      EXPECT_EQ(f[2][0], 0.0);
    } else {
      EXPECT_NEAR(f[1][0], -1000.0 * 0.004, 1e-9);    // overlap 2r - d = 0.004
      EXPECT_NEAR(f[2][0], 1000.0 * 0.004, 1e-9);
      auto r = rows();
      EXPECT_NEAR(r[1][FX], 0.0, 1e-12);
    }
  }
}

TEST_F(FixClumpRigidTest, PebbleVelocitiesGiveClumpMotion)
{
  commands(box_commands());
  commands("molecule asym " + asym_file + R"(
create_atoms 0 single 0 0 0 mol asym 13
pair_style zero 0.02
pair_coeff * *
velocity all set 0.1 -0.2 0.05
fix c all clump/rigid density 2500
run 0
)");
  auto r = rows();
  const double m = union_mass(asymmetric());
  EXPECT_NEAR(r[1][VX], 0.1, 1e-12);
  EXPECT_NEAR(r[1][VY], -0.2, 1e-12);
  EXPECT_NEAR(r[1][VZ], 0.05, 1e-12);
  EXPECT_NEAR(evaluate("f_c[2]") / (0.5 * m * (0.01 + 0.04 + 0.0025)), 1.0, 2e-5);
  EXPECT_NEAR(evaluate("f_c[3]"), 0.0, 1e-20);
  EXPECT_NEAR(evaluate("f_c[4]"), evaluate("f_c[2]"), 1e-20);
}

namespace {

// Sets up the asymmetric clump spinning with body-frame angular velocity w_body: the clump is
// created and set up once to learn its principal axes, then the fix is replaced with pebble
// velocities v = w x (x - xcm). Returns the principal moments (body x, y, z).
std::array<double, 3> spin_asymmetric(LammpsFixture &t, LAMMPS_NS::LAMMPS *lmp,
                                      const std::string &asym_file,
                                      const std::array<double, 3> &w_body,
                                      const std::string &integrator)
{
  auto run = [&](const std::string &s) {
    std::istringstream in(s);
    std::string line;
    while (std::getline(in, line))
      if (line.find_first_not_of(" \t") != std::string::npos) lmp->input->one(line);
  };
  run(box_commands());
  run("molecule asym " + asym_file + R"(
create_atoms 0 single 0 0 0 mol asym 13 rotate 30 1 2 3
pair_style zero 0.02
pair_coeff * *
timestep 1e-4
fix c all clump/rigid density 2500
run 0
)");
  auto r = clump_rows(lmp, "c").at(1);
  clump::Mat3 rot = clump::quat_to_matrix({r[QUATW], r[QUATI], r[QUATJ], r[QUATK]});
  clump::Vec3 w = clump::matvec(rot, {w_body[0], w_body[1], w_body[2]});
  char buf[1024];
  std::snprintf(buf, sizeof(buf), R"(
unfix c
variable vx atom %.17g*(z-(%.17g))-(%.17g)*(y-(%.17g))
variable vy atom %.17g*(x-(%.17g))-(%.17g)*(z-(%.17g))
variable vz atom %.17g*(y-(%.17g))-(%.17g)*(x-(%.17g))
velocity all set v_vx v_vy v_vz
fix c all clump/rigid density 2500 integrator %s
run 0
)",
                w[1], r[ZU], w[2], r[YU], w[2], r[XU], w[0], r[ZU], w[0], r[YU], w[1], r[XU],
                integrator.c_str());
  run(buf);
  (void) t;
  return {r[INERTIAX], r[INERTIAY], r[INERTIAZ]};
}

}    // namespace

// Torque-free asymmetric clump: the fitted initial motion is the imposed one, and kinetic
// energy and angular momentum stay constant over 1e5 steps (about 80 turns), with both
// integrators (rigid/small: Richardson quaternion update; rigid/nve/small: symplectic).
TEST_F(FixClumpRigidTest, TorqueFreeClumpConservesEnergyAndAngularMomentum)
{
  for (const std::string integ : {"small", "nve"}) {
    SCOPED_TRACE(integ);
    create();
    const std::array<double, 3> wb = {20.0, -35.0, 50.0};
    auto inertia = spin_asymmetric(*this, lmp, asym_file, wb, integ);
    ASSERT_GT(inertia[0], 1.05 * inertia[1]);    // three distinct moments
    ASSERT_GT(inertia[1], 1.05 * inertia[2]);
    double e_want = 0.5 * (inertia[0] * wb[0] * wb[0] + inertia[1] * wb[1] * wb[1] +
                           inertia[2] * wb[2] * wb[2]);
    double e0 = evaluate("f_c[3]");
    EXPECT_NEAR(e0 / e_want, 1.0, 1e-9);
    auto r0 = rows().at(1);
    double l0[3] = {r0[ANGMOMX], r0[ANGMOMY], r0[ANGMOMZ]};
    double lnorm = std::sqrt(l0[0] * l0[0] + l0[1] * l0[1] + l0[2] * l0[2]);
    command("run 100000");
    auto r1 = rows().at(1);
    // measured: 7e-6 (Richardson, small), 1e-7 (symplectic, nve)
    EXPECT_NEAR(evaluate("f_c[3]") / e0, 1.0, integ == "small" ? 2e-5 : 1e-6);
    EXPECT_NEAR(r1[ANGMOMX], l0[0], 1e-9 * lnorm);
    EXPECT_NEAR(r1[ANGMOMY], l0[1], 1e-9 * lnorm);
    EXPECT_NEAR(r1[ANGMOMZ], l0[2], 1e-9 * lnorm);
    EXPECT_NEAR(evaluate("f_c[2]"), 0.0, 1e-20);    // no drift of the centre of mass
    // it did rotate: orientation changed
    double dq = std::fabs(r1[QUATW] - r0[QUATW]) + std::fabs(r1[QUATI] - r0[QUATI]);
    EXPECT_GT(dq, 1e-2);
  }
}

// Dzhanibekov effect: spin about the intermediate principal axis with a small perturbation;
// the intermediate axis turns over (its projection on L changes sign) while energy and L stay.
TEST_F(FixClumpRigidTest, IntermediateAxisTurnsOver)
{
  auto inertia = spin_asymmetric(*this, lmp, asym_file, {0.05, 60.0, 0.05}, "small");
  int mid = 1;    // body axis of the intermediate moment
  std::array<int, 3> idx = {0, 1, 2};
  std::sort(idx.begin(), idx.end(), [&](int a, int b) { return inertia[a] < inertia[b]; });
  mid = idx[1];
  auto r0 = rows().at(1);
  double e0 = evaluate("f_c[3]");
  clump::Vec3 l = {r0[ANGMOMX], r0[ANGMOMY], r0[ANGMOMZ]};
  double ln = std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
  auto projection = [&]() {
    auto r = rows().at(1);
    clump::Mat3 rot = clump::quat_to_matrix({r[QUATW], r[QUATI], r[QUATJ], r[QUATK]});
    double p = 0;
    for (int d = 0; d < 3; ++d) p += rot[d][mid] * l[d] / ln;
    return p;
  };
  double p0 = projection();
  EXPECT_GT(std::fabs(p0), 0.99);
  double pmin = p0;
  int flips = 0;
  double sign = p0 > 0 ? 1 : -1;
  for (int k = 0; k < 50; ++k) {
    command("run 200 pre no post no");
    double p = projection();
    pmin = std::min(pmin * sign, p * sign) * sign;
    if (p * sign < -0.9) {
      ++flips;
      sign = -sign;
    }
  }
  EXPECT_GE(flips, 1) << "closest approach to the flipped state: " << pmin;
  EXPECT_NEAR(evaluate("f_c[3]") / e0, 1.0, 1e-5);
  auto r1 = rows().at(1);
  EXPECT_NEAR(r1[ANGMOMX], l[0], 1e-8 * ln);
  EXPECT_NEAR(r1[ANGMOMY], l[1], 1e-8 * ln);
  EXPECT_NEAR(r1[ANGMOMZ], l[2], 1e-8 * ln);
}

// Dipole clump (charges -1, 0, +1 on the x axis, p = 0.02 C m) in a uniform field E along y:
// torque p x E turns it like a pendulum, I phi'' = p E cos(phi), phi = angle of p from x.
// The pebble forces come from fix efield (post_force); rigid/small sums them into the clump
// force and torque after all forces are in, as it does with kspace forces.
TEST_F(FixClumpRigidTest, DipoleTurnsInUniformFieldAsTheTorqueSays)
{
  commands(box_commands());
  commands("molecule dip " + potentials + "/dipole3.mol" + R"(
create_atoms 0 single 0 0 0 mol dip 11 rotate 0 0 0 1
pair_style zero 0.02
pair_coeff * *
timestep 1e-4
fix ef all efield 0.0 1.0e-3 0.0
fix c all clump/rigid density 2500
run 0
)");
  auto dip = read_molecule(potentials + "/dipole3.mol");
  const double izz = principal_moments(dip)[2];    // transverse moment (largest)
  const double pE = 0.02 * 1.0e-3;
  auto r = rows().at(1);
  EXPECT_NEAR(r[TQZ], pE, 1e-12 * pE);
  EXPECT_NEAR(r[FX], 0.0, 1e-15);
  EXPECT_NEAR(r[FY], 0.0, 1e-15);
  // reference: RK4 of phi'' = (pE/I) cos(phi), phi(0) = 0, phi'(0) = 0
  double phi = 0.0, om = 0.0;
  const double h = 1e-5;
  auto acc = [&](double ph) { return pE / izz * std::cos(ph); };
  for (int chunk = 1; chunk <= 4; ++chunk) {
    command("run 500 pre no post no");
    for (int s = 0; s < 5000; ++s) {
      double k1p = om, k1o = acc(phi);
      double k2p = om + 0.5 * h * k1o, k2o = acc(phi + 0.5 * h * k1p);
      double k3p = om + 0.5 * h * k2o, k3o = acc(phi + 0.5 * h * k2p);
      double k4p = om + h * k3o, k4o = acc(phi + h * k3p);
      phi += h / 6 * (k1p + 2 * k2p + 2 * k3p + k4p);
      om += h / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
    }
    auto x = positions_by_id();
    double ang = std::atan2(x[3][1] - x[1][1], x[3][0] - x[1][0]);
    EXPECT_NEAR(ang, phi, 2e-4) << "after " << chunk * 500 << " steps";
    auto rr = rows().at(1);
    EXPECT_NEAR(rr[OMEGAZ], om, 2e-3 * std::fabs(om) + 1e-6);
  }
  EXPECT_GT(phi, 0.5);    // it turned a lot
}

// A fix that adds forces to the pebbles defined after fix clump/rigid: rigid/small sums the
// pebble forces at its set-up, before that fix's set-up adds its force, so the first half-step
// of every run lacks it: a warning that says to define it first; and a run split in two equals
// the unsplit run only in that order.
TEST_F(FixClumpRigidTest, ForceFixAfterTheClumpFixIsAWarning)
{
  auto run = [&](bool field_first, bool split) {
    create();
    commands(box_commands());
    commands("molecule dip " + potentials + "/dipole3.mol\ncreate_atoms 0 single 0 0 0 mol dip 11 rotate 0 0 0 1\n"
             "pair_style zero 0.02\npair_coeff * *\ntimestep 1e-4\n");
    const std::string field = "fix ef all efield 0.0 1.0e-3 0.0\n", clumps = "fix c all clump/rigid density 2500\n";
    commands(field_first ? field + clumps : clumps + field);
    const std::string log = captured(split ? "run 200 post no\nrun 200 post no" : "run 400 post no");
    return std::make_pair(log, positions_by_id());
  };
  const auto [log_after, x_after] = run(false, true);
  EXPECT_NE(log_after.find("WARNING: Fix clump/rigid c: fix efield ef adds forces to its pebbles but is defined "
                           "after it"),
            std::string::npos)
      << log_after;
  const auto [log_first, x_first] = run(true, true);
  EXPECT_EQ(log_first.find("defined after it"), std::string::npos) << log_first;
  EXPECT_LT(kifmm_test::relative_force_error(x_first, run(true, false).second), 1e-12);
  EXPECT_GT(kifmm_test::relative_force_error(x_after, run(false, false).second), 1e-9);
}

// A clump with net charge Q in a uniform field accelerates with Q E / M_union.
TEST_F(FixClumpRigidTest, ChargedClumpAcceleratesWithUnionMass)
{
  commands(box_commands());
  commands("molecule dim " + dimer_file + R"(
create_atoms 0 single 0 0 0 mol dim 12
set atom 1 charge 2.0e-3
set atom 2 charge 1.0e-3
pair_style zero 0.02
pair_coeff * *
timestep 1e-4
fix ef all efield 1.0 0.0 -0.5
fix c all clump/rigid density 2500
run 1000
)");
  const double m = union_mass(dimer()), t = 0.1, q = 3.0e-3;
  auto r = rows().at(1);
  EXPECT_NEAR(r[VX] / (q * 1.0 * t / m), 1.0, 2e-5);
  EXPECT_NEAR(r[VZ] / (q * -0.5 * t / m), 1.0, 2e-5);
}

// Long-range forces: with kspace kifmm (full pairwise Coulomb sum, no pair part) the clump
// force and torque are the sums over its pebbles of the inter-clump Coulomb forces (the
// intra-clump forces cancel), as rigid/small sums all pebble forces after kspace has added
// them. Two charged dipole clumps, compared with the direct sum.
TEST_F(FixClumpRigidTest, KspaceForcesOnPebblesSumIntoClumpForceAndTorque)
{
  const double q = 1e-6;
  auto dq = write_molecule("dipq", {{-0.01, 0, 0, 0.005, -q}, {0, 0, 0, 0.005, 0.0},
                                    {0.01, 0, 0, 0.005, q}});
  commands(box_commands(0.2, "f f f"));
  commands("molecule dq " + dq + R"(
create_atoms 0 single 0 0 0 mol dq 11 rotate 0 0 0 1
create_atoms 0 single 0.004 0.031 -0.006 mol dq 12 rotate 70 1 2 3
pair_style zero 0.02
pair_coeff * *
kspace_style kifmm 1e-8
fix c all clump/rigid density 2500
run 0
)");
  auto x = positions_by_id();
  ASSERT_EQ(x.size(), 6u);
  const double qi[7] = {0, -q, 0, q, -q, 0, q};
  const double k = lmp->force->qqrd2e;
  auto r = rows();
  for (int a = 0; a < 2; ++a) {
    double f[3] = {0, 0, 0}, t[3] = {0, 0, 0};
    const double c[3] = {r[a + 1][XU], r[a + 1][YU], r[a + 1][ZU]};
    for (int i = 3 * a + 1; i <= 3 * a + 3; ++i) {
      double fi[3] = {0, 0, 0};
      for (int j = 3 * (1 - a) + 1; j <= 3 * (1 - a) + 3; ++j) {
        double d[3] = {x[i][0] - x[j][0], x[i][1] - x[j][1], x[i][2] - x[j][2]};
        double rr = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int m = 0; m < 3; ++m) fi[m] += k * qi[i] * qi[j] * d[m] / (rr * rr * rr);
      }
      double arm[3] = {x[i][0] - c[0], x[i][1] - c[1], x[i][2] - c[2]};
      for (int m = 0; m < 3; ++m) f[m] += fi[m];
      t[0] += arm[1] * fi[2] - arm[2] * fi[1];
      t[1] += arm[2] * fi[0] - arm[0] * fi[2];
      t[2] += arm[0] * fi[1] - arm[1] * fi[0];
    }
    double fn = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    double tn = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    ASSERT_GT(fn, 0.0);
    SCOPED_TRACE(a);
    EXPECT_NEAR(r[a + 1][FX], f[0], 1e-6 * fn);
    EXPECT_NEAR(r[a + 1][FY], f[1], 1e-6 * fn);
    EXPECT_NEAR(r[a + 1][FZ], f[2], 1e-6 * fn);
    EXPECT_NEAR(r[a + 1][TQX], t[0], 1e-6 * tn);
    EXPECT_NEAR(r[a + 1][TQY], t[1], 1e-6 * tn);
    EXPECT_NEAR(r[a + 1][TQZ], t[2], 1e-6 * tn);
  }
  // and they move the clumps: momentum is conserved, the clumps attract or repel
  command("run 200");
  auto r1 = rows();
  double m1 = r1[1][MASS], m2 = r1[2][MASS];
  for (int k2 : {VX, VY, VZ}) EXPECT_NEAR(m1 * r1[1][k2] + m2 * r1[2][k2], 0.0, 1e-6 * m1 * std::fabs(r1[1][VY]) + 1e-18);
  EXPECT_GT(std::fabs(r1[1][VY]), 0.0);
}

// The intra-clump exclusion of the fix is also what kspace kifmm does (it leaves the pairs
// inside a clump out): no warning for it; other exclusions are not applied and named.
TEST_F(FixClumpRigidTest, KifmmWarnsOnlyAboutExclusionsItDoesNotApply)
{
  commands(box_commands(0.2, "f f f"));
  commands("molecule dim " + dimer_file + R"(
create_atoms 0 single 0 0 0 mol dim 11
create_atoms 0 single 0.05 0 0 mol dim 12
set group all charge 1e-6
pair_style zero 0.02
pair_coeff * *
kspace_style kifmm 1e-6
fix c all clump/rigid density 2500
)");
  std::string out = captured("run 0 post no");
  EXPECT_EQ(out.find("does not apply to the long-range sum"), std::string::npos) << out;
  out = captured("neigh_modify exclude molecule/inter all\nrun 0 post no");
  EXPECT_NE(out.find("WARNING: kspace_style kifmm sums all pairs: neigh_modify exclude "
                     "(molecule/inter all) does not apply"),
            std::string::npos)
      << out;
}

namespace {
// restitution of a linear spring-dashpot contact M x'' = -k x - c x'
double restitution(double m, double k, double c)
{
  double w0 = std::sqrt(k / m), zeta = c / (2 * std::sqrt(k * m));
  return std::exp(-zeta * M_PI / std::sqrt(1 - zeta * zeta)) + 0.0 * w0;
}
}    // namespace

// A flat-lying dimer falls onto a granular wall (hooke): both pebbles touch, M z'' =
// -2 kn z - 2 M gamman z', so it bounces with the restitution of that oscillator for the
// clump's union mass; without damping it keeps its energy.
TEST_F(FixClumpRigidTest, BouncesOffGranularWallAndLosesEnergyWithDamping)
{
  const double m = union_mass(dimer()), kn = 100.0;
  for (double gamman : {0.0, 60.0}) {
    SCOPED_TRACE(gamman);
    create();
    commands(box_commands(0.2, "p p f"));
    char buf[1024];
    std::snprintf(buf, sizeof(buf), R"(
molecule dim %s
create_atoms 0 single 0 0 -0.0945 mol dim 12 rotate 0 0 0 1
pair_style zero 0.02
pair_coeff * *
timestep 1e-5
velocity all set 0 0 -0.1
fix w all wall/gran hooke %g NULL %g NULL 0.0 0 zplane -0.1 NULL
fix c all clump/rigid density 2500
run 0
)",
                  dimer_file.c_str(), kn, gamman);
    commands(buf);
    double ke0 = evaluate("f_c[2]");
    EXPECT_NEAR(ke0 / (0.5 * m * 0.01), 1.0, 2e-5);
    command("run 3000");
    auto r = rows().at(1);
    ASSERT_GT(r[VZ], 0.0) << "it must bounce back up";
    ASSERT_GT(r[ZU] + 0.1, 0.0051) << "and have left the wall";
    double e = r[VZ] / 0.1;
    double want = restitution(m, 2 * kn, 2 * m * gamman);
    EXPECT_NEAR(e, want, 0.01);
    if (gamman > 0) EXPECT_LT(evaluate("f_c[4]"), 0.5 * ke0);
    else EXPECT_NEAR(evaluate("f_c[4]") / ke0, 1.0, 1e-3);
    EXPECT_NEAR(evaluate("f_c[3]"), 0.0, 1e-12 * ke0);    // no spin: symmetric contact
  }
}

// Clumps inserted by fix deposit from the molecule template get the union mass: the fix
// stores it in the template, rigid/small's set_molecule takes it from there.
TEST_F(FixClumpRigidTest, DepositedClumpsHaveUnionMass)
{
  commands(box_commands());
  commands("molecule dim " + dimer_file + R"(
pair_style zero 0.02
pair_coeff * *
region slab block -0.1 0.1 -0.1 0.1 -0.1 0.1
timestep 1e-4
fix c all clump/rigid density 2500 mol dim
fix d all deposit 3 0 10 4321 region slab mol dim rigid c near 0.02
run 25
)");
  EXPECT_EQ(evaluate("f_c[1]"), 3.0);
  auto r = rows();
  ASSERT_EQ(r.size(), 3u);
  const double m = union_mass(dimer());
  for (auto &[mol, row] : r) EXPECT_NEAR(row[MASS] / m, 1.0, 2e-5) << "clump " << mol;
}

// Clumps poured by fix pour (rigid keyword naming this fix) get the union mass, and with the
// gravity keyword fall with g whatever their pebbles' masses (fix gravity on no atoms gives
// the vector; rigid/small applies M g at the COM).
TEST_F(FixClumpRigidTest, PouredClumpsHaveUnionMassAndFallWithG)
{
  commands(box_commands(0.1, "p p f"));
  commands("molecule dip " + potentials + "/dipole3.mol" + R"(
pair_style zero 0.02
pair_coeff * *
timestep 1e-4
group nothing empty
fix grav nothing gravity 9.81 vector 0 0 -1
region slab block -0.08 0.08 -0.08 0.08 0.0 0.09
fix c all clump/rigid density 2500 mol dip gravity grav
fix p all pour 5 0 4767548 vol 0.05 50 region slab mol dip rigid c
run 1
)");
  EXPECT_EQ(evaluate("f_c[1]"), 5.0);
  auto r0 = rows();
  ASSERT_EQ(r0.size(), 5u);
  const double m = 3 * RHO * 4.0 / 3.0 * M_PI * std::pow(0.005, 3);
  for (auto &[mol, row] : r0) EXPECT_NEAR(row[MASS] / m, 1.0, 1e-5) << "clump " << mol;
  // rigid/small's setup() leaves gravity out of the first half-step of every run; fix
  // clump/rigid adds it back: each run gains exactly N g dt (no lag of g dt/2 per run)
  command("run 200");
  auto r1 = rows();
  command("run 400");
  auto r2 = rows();
  for (auto &[mol, row] : r2) {
    double dv200 = r1[mol][VZ] - r0[mol][VZ], dv400 = row[VZ] - r1[mol][VZ];
    EXPECT_NEAR(dv200, -9.81 * 200 * 1e-4, 1e-9) << "clump " << mol;
    EXPECT_NEAR(dv400, -9.81 * 400 * 1e-4, 1e-9) << "clump " << mol;
  }
}

// Pre-built clumps read from a data file get the same union mass properties and motion.
TEST_F(FixClumpRigidTest, ClumpsFromReadData)
{
  auto data = std::filesystem::path(dimer_file).parent_path() / "clumps.data";
  commands(box_commands());
  commands("molecule dim " + dimer_file + "\nmolecule asym " + asym_file + R"(
create_atoms 0 single 0 0 0 mol dim 12
create_atoms 0 single 0.05 0.01 0 mol asym 13
velocity all set 0.01 0.02 0.03
)");
  command("write_data " + data.string() + " nocoeff");
  create();
  commands(R"(
units si
atom_style hybrid sphere charge
atom_modify map array
fix prop all property/atom mol ghost yes
)");
  command("read_data " + data.string() + " fix prop NULL Molecules");
  commands(R"(
comm_modify cutoff 0.1 vel yes
pair_style zero 0.02
pair_coeff * *
thermo_style custom step
fix c all clump/rigid density 2500
run 0
)");
  auto r = rows();
  ASSERT_EQ(r.size(), 2u);
  EXPECT_NEAR(r[1][MASS] / union_mass(dimer()), 1.0, 2e-5);
  EXPECT_NEAR(r[2][MASS] / union_mass(asymmetric()), 1.0, 2e-5);
  EXPECT_NEAR(r[2][VY], 0.02, 1e-12);
}

// Explicit mass properties: infile (rigid/small's format) for existing clumps; templates must
// then carry mass, com and inertia in their header.
TEST_F(FixClumpRigidTest, ExplicitMassPropertiesFromInfileAndTemplateHeader)
{
  auto dir = scratch_dir();
  auto infile = (dir / "bodies.txt").string();
  std::ofstream(infile) << "# id mass x y z ixx iyy izz ixy ixz iyz vx vy vz lx ly lz ix iy iz\n"
                           "1\n"
                           "1 0.5 0 0 0 1e-5 2e-5 3e-5 0 0 0 0.1 0 0 0 0 0 0 0 0\n";
  std::string text;
  {
    std::ifstream f(dimer_file);
    text.assign(std::istreambuf_iterator<char>(f), {});
  }
  auto with_header = (dir / "dimer_header.mol").string();
  std::string h = text;
  h.insert(h.find("2 atoms"), "0.25 mass\n0 0 0 com\n1e-6 2e-6 2e-6 0 0 0 inertia\n");
  std::ofstream(with_header) << h;
  commands(box_commands());
  commands("molecule dim " + dimer_file + "\nmolecule dimh " + with_header + R"(
create_atoms 0 single 0 0 0 mol dim 12 rotate 0 0 0 1
pair_style zero 0.02
pair_coeff * *
region slab block -0.1 0.1 -0.1 0.1 -0.1 0.1
)");
  command("fix c all clump/rigid infile " + infile + " mol dimh");
  command("fix d all deposit 1 0 10 4321 region slab mol dimh rigid c near 0.02");
  command("run 5");
  auto r = rows();
  ASSERT_EQ(r.size(), 2u);
  EXPECT_DOUBLE_EQ(r[1][MASS], 0.5);
  EXPECT_NEAR(r[1][VX], 0.1, 1e-12);
  std::array<double, 3> in1 = {r[1][INERTIAX], r[1][INERTIAY], r[1][INERTIAZ]};
  std::sort(in1.begin(), in1.end());
  EXPECT_NEAR(in1[0], 1e-5, 1e-15);
  EXPECT_NEAR(in1[2], 3e-5, 1e-15);
  EXPECT_DOUBLE_EQ(r[2][MASS], 0.25);
}

TEST_F(FixClumpRigidTest, InfileModeNeedsTemplateMassPropertiesInHeader)
{
  commands(box_commands());
  command("molecule dim " + dimer_file);
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid infile nofile.txt mol dim"),
                      "molecule template dim must give mass, com and inertia in its header");
}

// rigid/small makes its bodies when the fix is defined: a clump created afterwards is not a
// body (LAMMPS's rule); the fix leaves it out of the body file (with a warning) instead of
// handing rigid/small an unknown body ID.
TEST_F(FixClumpRigidTest, ClumpsCreatedAfterTheFixAreLeftOut)
{
  commands(box_commands());
  commands("molecule dim " + dimer_file + R"(
create_atoms 0 single 0 0 0 mol dim 12
pair_style zero 0.02
pair_coeff * *
fix c all clump/rigid density 2500
create_atoms 0 single 0.05 0 0 mol dim 13
run 0
)");
  EXPECT_EQ(evaluate("f_c[1]"), 1.0);
  auto r = rows();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[1][MASS] / union_mass(dimer()), 1.0, 2e-5);
}

// ---------------------------------------------------------------- errors

TEST_F(FixClumpRigidTest, DuplicatePebblesInTemplateAreAnError)
{
  auto dup = write_molecule("dup", {{0, 0, 0, 0.005, 0}, {0.004, 0, 0, 0.005, 0},
                                    {0, 0, 0, 0.005, 0}});
  commands(box_commands());
  command("molecule dup " + dup);
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 2500 mol dup"),
                      "template dup: 1 pair\\(s\\) of duplicate \\(coincident\\) pebbles, "
                      "first: pebbles 1 and 3");
}

TEST_F(FixClumpRigidTest, DuplicatePebblesInClumpAreAnError)
{
  auto dup = write_molecule("dup", {{0, 0, 0, 0.005, 0}, {0.004, 0, 0, 0.005, 0},
                                    {0.004, 0, 0, 0.004, 0}});
  commands(box_commands());
  commands("molecule dup " + dup + R"(
create_atoms 0 single 0 0 0 mol dup 11
pair_style zero 0.02
pair_coeff * *
fix c all clump/rigid density 2500
)");
  EXPECT_LAMMPS_ERROR(command("run 0"),
                      "clump \\(molecule ID\\) 1: 1 pair\\(s\\) of duplicate \\(coincident\\) "
                      "pebbles, first: pebbles 2 and 3");
}

TEST_F(FixClumpRigidTest, TruncatedOrMalformedTemplateIsAnError)
{
  auto dir = std::filesystem::path(dimer_file).parent_path();
  std::string text;
  {
    std::ifstream f(potentials + "/dipole3.mol");
    text.assign(std::istreambuf_iterator<char>(f), {});
  }
  auto truncated = (dir / "truncated.mol").string();
  std::ofstream(truncated) << text.substr(0, text.find("Diameters") + 15);
  auto malformed = (dir / "malformed.mol").string();
  std::string bad = text;
  bad.replace(bad.find("2 0 0 0"), 7, "2 0 zero 0");
  std::ofstream(malformed) << bad;
  commands(box_commands());
  EXPECT_LAMMPS_ERROR(command("molecule t " + truncated),
                      "ERROR: Unexpected end of molecule file");
  EXPECT_LAMMPS_ERROR(command("molecule m " + malformed),
                      "ERROR: Invalid line in Coords section of molecule file.*'zero'");
  // a template without diameters cannot be a clump
  auto nodiam = (dir / "nodiam.mol").string();
  std::ofstream(nodiam) << text.substr(0, text.find("Diameters"));
  command("molecule nd " + nodiam);
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 2500 mol nd"),
                      "template nd needs Coords and Diameters");
}

// Regression of the fuzz target fuzz/fuzz_clump_template.cpp: LAMMPS's molecule reader takes
// "1e400" (an infinite coordinate) and 1e300 coordinates; fix clump/rigid refuses them with a
// message naming the template and the pebble (before: undefined behaviour in the duplicate
// search).
TEST_F(FixClumpRigidTest, TemplateWithOverflowingCoordinatesIsAnError)
{
  auto dir = std::filesystem::path(dimer_file).parent_path();
  auto inf = (dir / "inf.mol").string();
  std::ofstream(inf) << "# overflow\n\n2 atoms\n\nCoords\n\n1 0 0 0\n2 1e400 0 0\n\n"
                        "Diameters\n\n1 0.01\n2 0.01\n";
  auto far = (dir / "far.mol").string();
  std::ofstream(far) << "# far\n\n2 atoms\n\nCoords\n\n1 1e300 0 0\n2 -1e300 0 0\n\n"
                        "Diameters\n\n1 0.01\n2 0.01\n";
  commands(box_commands());
  command("molecule inf " + inf);
  command("molecule far " + far);
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 2500 mol inf"),
                      "ERROR: Fix clump/rigid molecule template inf: pebble 2 has a non-finite "
                      "coordinate \\(inf, 0, 0\\)");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 2500 mol far"),
                      "ERROR: Fix clump/rigid molecule template far: pebble 2 is farther than "
                      "1e\\+09 largest radii from pebble 1");
}

TEST_F(FixClumpRigidTest, AnotherRigidFixOnTheSameAtomsIsAnError)
{
  commands(box_commands());
  commands("molecule dim " + dimer_file + R"(
create_atoms 0 single -0.05 0 0 mol dim 12
create_atoms 0 single 0.05 0 0 mol dim 13
group first molecule 1
group second molecule 2
pair_style zero 0.02
pair_coeff * *
timestep 1e-5
)");
  // other atoms: both fixes run
  commands("fix c first clump/rigid density 2500\nfix r second rigid/small molecule\nrun 2");
  EXPECT_EQ(evaluate("f_c[1]"), 1.0);
  commands("unfix r");
  // LAMMPS would stop later with "Lost atoms" or a missing body atom
  command("fix r all rigid/nve/small molecule");
  EXPECT_LAMMPS_ERROR(command("run 2"),
                      "ERROR: Fix clump/rigid c and fix r \\(rigid/nve/small\\) act on the same "
                      "atoms \\(groups first and all\\)");
  commands("unfix r\nfix r first rigid single");
  EXPECT_LAMMPS_ERROR(command("run 2"), "Fix clump/rigid c and fix r \\(rigid\\) act on the same");
  // another clump fix (through its internal rigid fix c2_rigid) is named as itself
  commands("unfix r\nfix c2 all clump/rigid density 2500");
  EXPECT_LAMMPS_ERROR(command("run 2"),
                      "Fix clump/rigid c and fix c2 \\(clump/rigid\\) act on the same atoms");
}

TEST_F(FixClumpRigidTest, BadArgumentsAreErrors)
{
  commands(box_commands());
  commands("molecule dim " + dimer_file + R"(
create_atoms 0 single 0 0 0 mol dim 12
pair_style zero 0.02
pair_coeff * *
)");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid"), "expected density <rho> or infile");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density -1"), "density must be > 0");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 1 tol 0.5"), "tol must be in");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 1 integrator verlet"),
                      "integrator must be small or nve");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 1 mol nosuch"),
                      "template nosuch does not exist");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 1 infile x.txt"),
                      "exactly one of the keywords density and infile");
  // a pebble outside any clump (molecule ID 0)
  command("create_atoms 1 single 0.1 0.1 0.1");
  EXPECT_LAMMPS_ERROR(command("fix c all clump/rigid density 1"), "molecule ID > 0");
}
