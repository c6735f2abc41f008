// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point dipoles in kspace_style kifmm (open boundaries) against LAMMPS's own exact sum of the
// same physics: pair lj/cut/dipole/cut with epsilon 0 and a Coulomb cutoff beyond the box
// (charge-charge, charge-dipole and dipole-dipole terms). Forces, torques, energy, pressure
// tensor, the order chosen for a requested accuracy, energy conservation under fix nve/sphere
// update dipole, and the clear errors of what the dipole sum does not cover. Under mpiexec the
// same comparisons hold on several ranks.
#include "kspace_kifmm.h"
#include "lammps_fixture.h"

#include "force.h"
#include "lammps.h"

#include <cmath>
#include <cstdio>

using namespace kifmm_test;

namespace {

class KSpaceDipoles : public LammpsFixture {
 protected:
  // k^3 spheres on a jittered simple cubic lattice of spacing 1.25 in an open box: type 1
  // charge and dipole, type 2 charge only, type 3 dipole only
  void spheres(int k, const std::string &boundary = "f f f")
  {
    const double h = 0.625 * k + 1.0;
    const std::string lo = std::to_string(-h), hi = std::to_string(h);
    commands("units lj\natom_style hybrid sphere dipole\nboundary " + boundary + "\natom_modify map array\n"
             "lattice sc 1.25\nregion box block " + lo + " " + hi + " " + lo + " " + hi + " " + lo + " " + hi +
             " units box\ncreate_box 3 box\nregion inner block 0 " + std::to_string(k - 1) + " 0 " +
             std::to_string(k - 1) + " 0 " + std::to_string(k - 1) + "\n"
             "create_atoms 1 region inner\ndisplace_atoms all move " + std::to_string(-0.625 * (k - 1)) + " " +
             std::to_string(-0.625 * (k - 1)) + " " + std::to_string(-0.625 * (k - 1)) + " units box\n"
             "displace_atoms all random 0.15 0.15 0.15 4711 units box\n"
             "set type 1 type/fraction 2 0.35 99\nset type 1 type/fraction 3 0.45 98\n"
             "set type 1 charge 1.0\nset type 2 charge -1.2\nset type 3 charge 0.0\n"
             "set type 1*3 dipole/random 4242 0.8\nset type 2 dipole 0 0 0\n"
             "thermo_style custom step pe elong press pxx pyy pzz pxy pxz pyz\nthermo_modify norm no\n"
             "neighbor 0.3 bin\nneigh_modify one 10000 page 200000\n");
  }
  struct Result {
    std::map<int, Vec3> f, t;
    double energy = 0, p[6] = {0, 0, 0, 0, 0, 0};
  };
  Result collect(const char *energy)
  {
    Result r{forces_by_id(), torques_by_id(), thermo(energy)};
    const char *keys[6] = {"pxx", "pyy", "pzz", "pxy", "pxz", "pyz"};
    for (int c = 0; c < 6; ++c) r.p[c] = thermo(keys[c]);
    return r;
  }
  Result exact()
  {
    commands("kspace_style none\npair_style lj/cut/dipole/cut 1.0 40.0\npair_coeff * * 0.0 1.0\nrun 0 post no");
    return collect("pe");
  }
  Result kifmm(const std::string &accuracy, const std::string &modify = "")
  {
    commands("pair_style zero 1.0\npair_coeff * *\nkspace_style kifmm " + accuracy);
    if (!modify.empty()) command("kspace_modify kifmm " + modify);
    command("run 0 post no");
    return collect("elong");
  }
  LAMMPS_NS::KSpaceKIFMM *kspace() { return dynamic_cast<LAMMPS_NS::KSpaceKIFMM *>(lmp->force->kspace); }
};

double rel(double a, double b)
{
  return std::fabs(a - b) / std::fabs(b);
}

// the order chosen for the request meets it on forces and torques; the energy follows
TEST_F(KSpaceDipoles, ForcesTorquesAndEnergyMeetTheRequest)
{
  spheres(11);
  const Result ref = exact();
  // the automatic tree (for this few atoms it may be one leaf: a direct sum) and a forced deep
  // one, so that the order chosen is tested with its far field
  for (const char *leaf : {"", "leaf 16"})
    for (const char *acc : {"1e-4", "1e-6", "1e-8"}) {
      const Result r = kifmm(acc, leaf);
      const double ef = relative_force_error(r.f, ref.f), et = relative_force_error(r.t, ref.t);
      std::printf("  accuracy %s %-7s: order %d, force error %.2e, torque error %.2e, energy error %.2e\n", acc,
                  leaf, kspace()->engine_order(), ef, et, rel(r.energy, ref.energy));
      EXPECT_LE(ef, std::stod(acc)) << acc << " " << leaf;
      EXPECT_LE(et, std::stod(acc)) << acc << " " << leaf;
      EXPECT_LE(rel(r.energy, ref.energy), 10 * std::stod(acc)) << acc << " " << leaf;
    }
}

// a high explicit order: equal to the exact sum to 1e-9, pressure tensor included (the virial
// sum_i x_i F_i of an open system is the pair style's sum_{i<j} r_ij F_ij)
TEST_F(KSpaceDipoles, HighOrderEqualsTheExactSumWithThePressureTensor)
{
  spheres(9);
  const Result ref = exact();
  const Result r = kifmm("1e-10", "order 12 leaf 32");
  EXPECT_LE(relative_force_error(r.f, ref.f), 1e-9);
  EXPECT_LE(relative_force_error(r.t, ref.t), 1e-9);
  EXPECT_LE(rel(r.energy, ref.energy), 1e-10);
  // the virial sums x_i F_i, which cancel to a pressure much smaller than their own size:
  // the scale of the error is sum_i |x_i| |F_i| / 3V
  double scale = 0;
  const auto x = positions_by_id();
  for (const auto &[id, f] : ref.f)
    scale += std::sqrt(x.at(id)[0] * x.at(id)[0] + x.at(id)[1] * x.at(id)[1] + x.at(id)[2] * x.at(id)[2]) *
             std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  scale /= 3.0 * evaluate("vol");
  for (int c = 0; c < 6; ++c) EXPECT_NEAR(r.p[c], ref.p[c], 1e-9 * scale) << "pressure component " << c;
}

// kspace_modify kifmm check: the measured error is that of forces and torques
TEST_F(KSpaceDipoles, CheckMeasuresForcesAndTorques)
{
  spheres(10);
  const Result ref = exact();
  commands("pair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-5\n"
           "kspace_modify kifmm order 4 leaf 16 check 1 300\nrun 0 post no");
  const Result r = collect("elong");
  const double actual = std::max(relative_force_error(r.f, ref.f), relative_force_error(r.t, ref.t));
  const double measured = evaluate("v_kifmm_error");
  std::printf("  order 4: measured %.3e, actual %.3e\n", measured, actual);
  EXPECT_GT(measured, 0.3 * actual);
  EXPECT_LT(measured, 3.0 * actual);
}

// fix nve/sphere update dipole: the drift of the total energy (with the rotational one; a tree
// of leaves of 16, not one leaf) of kifmm at 1e-7 is that of the exact sum
TEST_F(KSpaceDipoles, NveSphereConservesEnergyAsTheExactSum)
{
  auto run = [&](const std::string &interaction) {
    create();
    spheres(7, "s s s");
    commands("velocity all create 0.5 777 loop geom\nfix nve all nve/sphere update dipole\ntimestep 0.002\n"
             "compute erot all erotate/sphere\nvariable etot equal etotal+c_erot\n"
             "thermo_style custom step pe etotal c_erot v_etot\nthermo_modify norm no\n");
    commands(interaction);
    command("run 0 post no");
    const double e0 = evaluate("v_etot");    // translational and rotational kinetic energy
    double maxdev = 0;
    for (int k = 0; k < 5; ++k) {
      command("run 100 post no");
      maxdev = std::max(maxdev, std::fabs(evaluate("v_etot") - e0));
    }
    return maxdev / std::fabs(e0);
  };
  // soft repulsion keeps the spheres apart in both runs
  const double direct = run("pair_style hybrid/overlay soft 1.0 lj/cut/dipole/cut 1.0 40.0\n"
                            "pair_coeff * * soft 20.0\npair_coeff * * lj/cut/dipole/cut 0.0 1.0");
  const double fmm = run("pair_style soft 1.0\npair_coeff * * 20.0\nkspace_style kifmm 1e-7\nkspace_modify kifmm leaf 16");
  std::printf("  NVE/sphere 500 steps: relative energy drift direct %.3e, kifmm(1e-7) %.3e\n", direct, fmm);
  EXPECT_LE(fmm, 2.0 * direct + 1e-7);
}

// ---------------------------------------------------------------- errors

class KSpaceDipoleErrors : public KSpaceDipoles {};

TEST_F(KSpaceDipoleErrors, GravityHasNoDipoles)
{
  spheres(3);
  commands("pair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-4\nkspace_modify kifmm kernel gravity 1.0");
  EXPECT_LAMMPS_ERROR(command("run 0"), "kernel gravity has no dipoles");
}

TEST_F(KSpaceDipoleErrors, PeriodicBoundariesNeedOpenOnes)
{
  commands("units lj\natom_style hybrid sphere dipole\nboundary p p p\nregion box block 0 4 0 4 0 4\n"
           "create_box 1 box\ncreate_atoms 1 single 1 1 1\ncreate_atoms 1 single 3 3 3\n"
           "set atom 1 charge 1.0\nset atom 2 charge -1.0\nset atom 1 dipole 0 0 1\n"
           "pair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-4");
  EXPECT_LAMMPS_ERROR(command("run 0"), "point dipoles .* need open boundaries");
}

TEST_F(KSpaceDipoleErrors, AtomStyleWithoutTorqueIsAnError)
{
  commands("units lj\natom_style dipole\nboundary f f f\nregion box block 0 4 0 4 0 4\n"
           "create_box 1 box\ncreate_atoms 1 single 1 1 1\ncreate_atoms 1 single 3 3 3\nmass 1 1.0\n"
           "set atom 1 dipole 0 0 1\npair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-4");
  EXPECT_LAMMPS_ERROR(command("run 0"), "need atom attribute torque");
}

TEST_F(KSpaceDipoleErrors, StrideFixIsAnError)
{
  spheres(3);
  commands("pair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-4\nfix s all kifmm/stride 2");
  EXPECT_LAMMPS_ERROR(command("run 0"), "fix kifmm/stride does not support point dipoles");
}

TEST_F(KSpaceDipoleErrors, PerAtomVirialIsAnError)
{
  spheres(3);
  commands("pair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-4\ncompute s all stress/atom NULL\n"
           "compute r all reduce sum c_s[1]\nthermo_style custom step c_r");
  EXPECT_LAMMPS_ERROR(command("run 0"), "per-atom virial .* with point dipoles");
}

}    // namespace
