// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix kifmm/dielectric: dielectric spheres polarized by a uniform field, by the boundary
// integral equation. Two touching spheres against the exact two-sphere solution (the multipole
// reference of the engine tests) in LAMMPS units, the force against the numerical derivative
// of the fix's energy, the medium's permittivity (dielectric command), and the clear errors.
// Under mpiexec the same comparisons hold on several ranks.
#include "lammps_fixture.h"
#include "two_dielectric_spheres.h"

#include <cmath>

using namespace kifmm_test;

namespace {

class Dielectric : public LammpsFixture {
 protected:
  // two spheres of radius 1, centres d apart along the unit vector u, centred at (0.2, -0.1, 0.3)
  void pair(double d, const double u[3], const std::string &boundary = "f f f")
  {
    std::string s = "units lj\natom_style sphere\natom_modify map array\nboundary " + boundary +
        "\nregion box block -6 6 -6 6 -6 6\ncreate_box 1 box\n";
    for (int k = 0; k < 2; ++k) {
      const double sg = k ? -0.5 : 0.5;
      s += "create_atoms 1 single " + std::to_string(0.2 + sg * d * u[0]) + " " + std::to_string(-0.1 + sg * d * u[1]) +
          " " + std::to_string(0.3 + sg * d * u[2]) + " units box\n";
    }
    s += "set group all diameter 2.0\nset group all density 1.0\npair_style zero 3.0\npair_coeff * *\n";
    commands(s);
  }
  Vec3 force(int id) { return forces_by_id().at(id); }
};

const double kU[3] = {0.48, 0.6, 0.64};    // unit vector, none of the axes

}    // namespace

TEST_F(Dielectric, TouchingPairMatchesTheExactSolution)
{
  // touching spheres, permittivity 10, field 2 along their line of centres: the force is the
  // exact one (engine units: per unit field, sigma / (4 pi qqrd2e)) within 1 %
  pair(2.0, kU);
  commands("fix d all kifmm/dielectric permittivity 10 field " + std::to_string(2 * kU[0]) + " " +
           std::to_string(2 * kU[1]) + " " + std::to_string(2 * kU[2]) +
           "\nfix_modify d energy yes\nthermo_style custom step pe f_d f_d[1] f_d[2]\nrun 0");
  const double exact = 4.0 * kifmm_points::two_sphere_force(1, 2, 10, 1, 400) / (4 * M_PI);
  const Vec3 f1 = force(1), f2 = force(2);
  const double along = f1[0] * kU[0] + f1[1] * kU[1] + f1[2] * kU[2];
  EXPECT_LT(std::fabs(along / exact - 1), 1e-2) << along << " against " << exact;
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(f1[d], -f2[d], 1e-9 * std::fabs(exact));
    EXPECT_NEAR(f1[d], along * kU[d], 1e-6 * std::fabs(exact));
  }
  EXPECT_LE(evaluate("f_d[2]"), 1e-6);    // GMRES residual
  EXPECT_GT(evaluate("f_d[1]"), 0);
  // the energy -1/2 sum mu . E of the per-atom dipoles
  commands("compute mu all reduce sum f_d[1] f_d[2] f_d[3]\nthermo_style custom step f_d c_mu[1] c_mu[2] c_mu[3]\nrun 0");
  const double mu_e = 2 * (evaluate("c_mu[1]") * kU[0] + evaluate("c_mu[2]") * kU[1] + evaluate("c_mu[3]") * kU[2]);
  EXPECT_NEAR(evaluate("f_d"), -0.5 * mu_e, 1e-12 * std::fabs(mu_e));
  EXPECT_GT(evaluate("c_mu[1]") / kU[0], 2 * (9.0 / 12.0) * 2);    // more than two isolated spheres' dipoles
}

TEST_F(Dielectric, ForceIsMinusTheEnergyDerivative)
{
  // a gap of 0.3 radii, field at an angle to the pair: F_1 = -dU/dx_1 by central differences
  const double d = 2.3, h = 1e-4;
  auto energy = [&](double dx) {
    destroy();
    create();
    pair(d, kU);
    commands("displace_atoms all move 0 0 0 units box\ngroup one id 1\ndisplace_atoms one move " + std::to_string(dx) +
             " 0 0 units box\nfix d all kifmm/dielectric permittivity 6 field 0.3 -0.5 0.8 degree 12 tol 1e-12\n"
             "fix_modify d energy yes\nthermo_style custom step pe\nthermo_modify norm no\nrun 0");
    return thermo("pe");
  };
  const double up = energy(h), down = energy(-h);
  energy(0.0);
  const double fx = force(1)[0], numeric = -(up - down) / (2 * h);
  EXPECT_NEAR(fx, numeric, 1e-5 * std::fabs(fx) + 1e-9) << fx << " against " << numeric;
}

TEST_F(Dielectric, MediumPermittivityScalesTheForce)
{
  // permittivity 20 in a medium of 2 (dielectric command): the same ratio 10, the force twice
  // that in a medium of 1 (force ~ eps_m E^2 a^2)
  pair(2.2, kU);
  commands("fix d all kifmm/dielectric permittivity 10 field 0 0 1\nrun 0");
  const Vec3 f1 = force(1);
  destroy();
  create();
  pair(2.2, kU);
  commands("dielectric 2.0\nfix d all kifmm/dielectric permittivity 20 field 0 0 1\nrun 0");
  const Vec3 f2 = force(1);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(f2[d], 2 * f1[d], 1e-10 * std::fabs(f1[2]));
}

TEST_F(Dielectric, EveryHoldsTheForcesBetweenSolves)
{
  // every 3: the forces of step 0 held at steps 1 and 2 while the spheres move; solved again at
  // step 3 (equal to a solve at those positions)
  auto start = [&]() {
    pair(2.3, kU);
    commands("group one id 1\nvelocity one set 0.3 -0.2 0.5 units box\nfix nve all nve/sphere\ntimestep 0.05\n"
             "fix d all kifmm/dielectric permittivity 10 field 0 0 1 degree 8 every 3");
  };
  start();
  command("run 0");
  const Vec3 f0 = force(1);
  command("run 2");
  const Vec3 f2 = force(1);
  for (int d = 0; d < 3; ++d) EXPECT_EQ(f2[d], f0[d]);
  destroy();
  create();
  start();
  command("run 3");
  const Vec3 f3 = force(1);
  command("run 0");
  const Vec3 ref = force(1);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(f3[d], ref[d], 1e-12 * std::fabs(ref[2]));
  EXPECT_GT(std::fabs(f3[2] - f0[2]), 1e-6 * std::fabs(f0[2]));
}

using DielectricErrors = Dielectric;

TEST_F(DielectricErrors, ClearErrors)
{
  pair(2.5, kU, "p f f");
  commands("fix d all kifmm/dielectric permittivity 10 field 0 0 1");
  EXPECT_LAMMPS_ERROR(command("run 0"), "open boundaries only");
  EXPECT_LAMMPS_ERROR(command("fix e all kifmm/dielectric permittivity 10"), "the field is missing");
  EXPECT_LAMMPS_ERROR(command("fix e all kifmm/dielectric field 0 0 1"), "the permittivity is missing");
  EXPECT_LAMMPS_ERROR(command("fix e all kifmm/dielectric permittivity -1 field 0 0 1"), "must be positive");
  EXPECT_LAMMPS_ERROR(command("fix e all kifmm/dielectric permittivity 2 field 0 0 1 degree 0"), "degree 0 must be");
  EXPECT_LAMMPS_ERROR(command("fix e all kifmm/dielectric permittivity 2 field 0 0 1 overlap maybe"), "overlap must be touch or error");
  EXPECT_LAMMPS_ERROR(command("fix e all kifmm/dielectric permittivity 2 field 0 0 1 every 0"), "every 0 must be positive");
}

TEST_F(DielectricErrors, OverlapNamesTheAtoms)
{
  pair(1.9, kU);
  commands("fix d all kifmm/dielectric permittivity 10 field 0 0 1 overlap error");
  EXPECT_LAMMPS_ERROR(command("run 0"), "the spheres of atoms 1 and 2 overlap");
}

TEST_F(Dielectric, OverlapsAreSolvedAsTouching)
{
  // an overlap of 0.1 radii: solved as two touching spheres of radius 0.95 (overlap touch, the
  // default), the same forces as spheres of that radius; with shrink 0.05 as well
  pair(1.9, kU);
  commands("fix d all kifmm/dielectric permittivity 10 field 0 0 1\nrun 0");
  const Vec3 f = force(1);
  EXPECT_EQ(evaluate("f_d[4]"), 1.0);
  destroy();
  create();
  pair(1.9, kU);
  commands("set group all diameter 1.9\nfix d all kifmm/dielectric permittivity 10 field 0 0 1\nrun 0");
  const Vec3 g = force(1);
  EXPECT_EQ(evaluate("f_d[4]"), 0.0);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(f[d], g[d], 1e-8 * std::fabs(g[2]));
  destroy();
  create();
  pair(1.9, kU);
  commands("fix d all kifmm/dielectric permittivity 10 field 0 0 1 shrink 0.05 overlap error\nrun 0");
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(force(1)[d], g[d], 1e-6 * std::fabs(g[2]));
}

TEST_F(DielectricErrors, NeedsRadii)
{
  commands("units lj\natom_style atomic\nregion box block -3 3 -3 3 -3 3\ncreate_box 1 box\n"
           "create_atoms 1 single 0 0 0\nmass 1 1.0\npair_style zero 1.0\npair_coeff * *\n"
           "fix d all kifmm/dielectric permittivity 10 field 0 0 1");
  EXPECT_LAMMPS_ERROR(command("run 0"), "needs atom radii");
}
