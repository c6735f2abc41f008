// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Hard cases and bad input for kspace_style kifmm: empty and tiny systems, everything at one
// point, coincident atoms, non-finite charges, memory refusal, high orders.
#include "configurations.h"
#include "kspace_kifmm.h"
#include "lammps_fixture.h"

#include "atom.h"
#include "force.h"
#include "lammps.h"

#include <cmath>
#include <cstdlib>

using namespace kifmm_test;

namespace {

class HardCases : public LammpsFixture {
 protected:
  void box(const std::string &extra = "")
  {
    commands("units lj\natom_style charge\nboundary f f f\natom_modify map array\n"
             "region box block 0 1 0 1 0 1\ncreate_box 1 box\nmass 1 1.0\n"
             "pair_style zero 0.01\npair_coeff * *\nthermo_style custom step pe elong\n"
             "thermo_modify norm no lost ignore\nneigh_modify one 10000 page 200000\n" + extra);
  }
  LAMMPS_NS::KSpaceKIFMM *kspace()
  {
    return dynamic_cast<LAMMPS_NS::KSpaceKIFMM *>(lmp->force->kspace);
  }
  void all_finite()
  {
    for (auto &[id, f] : forces_by_id())
      for (double v : f) ASSERT_TRUE(std::isfinite(v)) << "atom " << id;
  }
};

TEST_F(HardCases, ZeroAtoms)
{
  box("kspace_style kifmm 1e-5\nrun 0 post no");
  EXPECT_EQ(thermo("elong"), 0.0);
}

TEST_F(HardCases, OneAtom)
{
  box("create_atoms 1 single 0.5 0.5 0.5\nset atom 1 charge 2.0\nkspace_style kifmm 1e-5\n"
      "run 0 post no");
  EXPECT_EQ(thermo("elong"), 0.0);
  EXPECT_EQ(forces_by_id()[1], (Vec3{0, 0, 0}));
}

TEST_F(HardCases, AllAtomsWithin1e9OfOnePoint)
{
  // 300 charges in a cube of side 1e-9: the tree stops at its depth limit, no NaN, and the
  // forces equal the exact direct sum
  box();
  Configuration c = uniform_cube(300, 77);
  for (int i = 0; i < 300; ++i) {
    commands("create_atoms 1 single " + std::to_string(0.5 + 1e-9 * c.x[i][0]) + " " +
             std::to_string(0.5 + 1e-9 * c.x[i][1]) + " " + std::to_string(0.5 + 1e-9 * c.x[i][2]) +
             " units box");
  }
  // std::to_string keeps 6 decimals: set exact positions directly
  double **x = lmp->atom->x;
  for (int i = 0; i < lmp->atom->nlocal; ++i) {
    const int id = lmp->atom->tag[i] - 1;
    for (int d = 0; d < 3; ++d) x[i][d] = 0.5 + 1e-9 * c.x[id][d];
    lmp->atom->q[i] = c.q[id];
  }
  commands("pair_style coul/cut 0.5\npair_coeff * *\nrun 0 post no");
  auto exact = forces_by_id();
  const double e_exact = thermo("pe");
  commands("pair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-6\nrun 0 post no");
  all_finite();
  EXPECT_LE(relative_force_error(forces_by_id(), exact), 1e-6);
  EXPECT_NEAR(thermo("elong"), e_exact, 1e-6 * std::fabs(e_exact));
}

TEST_F(HardCases, CoincidentAtomsAreExcludedAndReported)
{
  // atoms 1 and 2 at the same point: their pair is excluded; every other atom sees them as
  // one atom of charge q1 + q2 (compared with that system through coul/cut)
  Configuration c = uniform_cube(500, 5);
  c.x[1] = c.x[0];
  c.q[0] = 1.0;
  c.q[1] = 0.5;
  const std::string path = testing::TempDir() + "kifmm_coincident.data";
  write_charge_data(path, c);
  commands("units lj\natom_style charge\nboundary f f f\natom_modify map array\nread_data " +
           path + "\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-7\n"
           "thermo_style custom step pe elong\nthermo_modify norm no");
  const std::string out = captured("run 0 post no");
  EXPECT_NE(out.find("at zero distance are excluded"), std::string::npos) << out;
  EXPECT_GT(kspace()->engine_stats().coincident_pairs, 0u);
  all_finite();
  auto fmm = forces_by_id();
  const double e_fmm = thermo("elong");

  // the same physics without the coincident pair: merge atom 2 into atom 1
  Configuration merged = c;
  merged.q[0] = 1.5;
  merged.q[1] = 0.0;                      // uncharged, and moved away so that coul/cut
  merged.x[1] = {0.999, 0.001, 0.999};    // does not divide 0 by 0
  write_charge_data(path, merged);
  create();
  commands("units lj\natom_style charge\nboundary f f f\natom_modify map array\nread_data " +
           path + "\npair_style coul/cut 5.0\npair_coeff * *\nthermo_style custom step pe\n"
           "thermo_modify norm no\nrun 0 post no");
  auto exact = forces_by_id();
  std::remove(path.c_str());
  // atom 1 and 2 together feel the merged atom's force; the others the same force
  Vec3 sum12 = {fmm[1][0] + fmm[2][0], fmm[1][1] + fmm[2][1], fmm[1][2] + fmm[2][2]};
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(sum12[d], exact[1][d], 1e-6 * std::fabs(exact[1][d]) + 1e-9);
  fmm.erase(1);
  fmm.erase(2);
  exact.erase(1);
  exact.erase(2);
  EXPECT_LE(relative_force_error(fmm, exact), 1e-7);
  // the energy excludes the zero-distance pair: E_fmm = E_merged - q1 q2 * (1/0 term absent)
  // differs from E_merged only by the undefined self term, so it is only required finite
  EXPECT_TRUE(std::isfinite(e_fmm));
}

TEST_F(HardCases, NonFiniteChargeNamesTheAtom)
{
  box("create_atoms 1 single 0.2 0.2 0.2\ncreate_atoms 1 single 0.7 0.7 0.7\n"
      "set atom 1 charge 1.0\nkspace_style kifmm 1e-4");
  lmp->atom->q[1] = NAN;
  const int id = lmp->atom->tag[1];
  EXPECT_EXIT(
      {
        screen_to_stderr(lmp);
        command("run 0 post no");
      },
      ::testing::ExitedWithCode(1), "atom " + std::to_string(id) + " has a non-finite charge");
}

TEST_F(HardCases, MemoryBeyondTheLimitIsRefusedWithTheEstimate)
{
  box("create_atoms 1 random 2000 1 box\nset group all charge 1.0\nkspace_style kifmm 1e-4");
  setenv("KIFMM_MEMORY_LIMIT_MB", "0.001", 1);
  EXPECT_LAMMPS_ERROR(command("run 0 post no"),
                      "estimated memory [0-9]+ MB for 2000 atoms at order [0-9]+ exceeds the 0 MB");
  unsetenv("KIFMM_MEMORY_LIMIT_MB");
}

TEST_F(HardCases, HighOrdersKeepImproving)
{
  // the error keeps falling up to order 14 through LAMMPS (no blow-up of the pseudo-inverses)
  Configuration c = plummer(3000, 12, 0.1);
  const std::string path = testing::TempDir() + "kifmm_orders.data";
  write_charge_data(path, c);
  commands("units lj\natom_style charge\nboundary f f f\nread_data " + path +
           "\nneigh_modify one 10000 page 200000\nthermo_modify norm no\npair_style coul/cut 5.0\npair_coeff * *\nrun 0 post no");
  auto exact = forces_by_id();
  commands("pair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-3");
  double last = 1.0;
  for (int p : {4, 6, 8, 10, 12, 14}) {
    command("kspace_modify kifmm order " + std::to_string(p) + " leaf 64");
    command("run 0 post no");
    double err = relative_force_error(forces_by_id(), exact);
    printf("  order %2d: relative force error %.2e\n", p, err);
    EXPECT_LT(err, last) << "order " << p;
    last = std::max(err, 1e-14);
  }
  EXPECT_LT(last, 1e-9);
  std::remove(path.c_str());
}

}    // namespace

namespace {

TEST_F(HardCases, TriclinicBoxIsAClearError)
{
  commands("units lj\natom_style charge\nboundary f f f\n"
           "region box prism 0 1 0 1 0 1 0.1 0 0\ncreate_box 1 box\nmass 1 1.0\n"
           "create_atoms 1 single 0.5 0.5 0.5\npair_style zero 0.01\npair_coeff * *\n"
           "kspace_style kifmm 1e-4");
  EXPECT_LAMMPS_ERROR(command("run 0"), "kifmm does not support triclinic boxes");
}

TEST_F(HardCases, Dimension2IsAClearError)
{
  // a cubic periodic box: without the check the 3-d periodic sum would run
  commands("units lj\ndimension 2\natom_style charge\nboundary p p p\n"
           "region box block 0 1 0 1 -0.5 0.5\ncreate_box 1 box\nmass 1 1.0\n"
           "create_atoms 1 single 0.2 0.2 0.0\ncreate_atoms 1 single 0.7 0.6 0.0\n"
           "set atom 1 charge 1.0\nset atom 2 charge -1.0\npair_style zero 0.01\n"
           "pair_coeff * *\nkspace_style kifmm 1e-4");
  EXPECT_LAMMPS_ERROR(command("run 0"), "kifmm does not support dimension 2: its kernels");
}

TEST_F(HardCases, NonFiniteCoordinateStopsTheRunWithAnError)
{
  box("create_atoms 1 single 0.2 0.2 0.2\ncreate_atoms 1 single 0.7 0.7 0.7\n"
      "set group all charge 1.0\nkspace_style kifmm 1e-4\nrun 0 post no");
  lmp->atom->x[1][0] = NAN;
  EXPECT_LAMMPS_ERROR(command("run 1 post no"), "ERROR.*(Non-numeric|non-finite)");
}

}    // namespace
