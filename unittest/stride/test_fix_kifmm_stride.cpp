// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix kifmm/stride: schedule (hold, impulse, energy last/every), N = 1 equals no fix bit for
// bit, restart split, cache through sort/delete/insert, clumps (fix rigid/small) receive the
// held forces, stiffness probe and recommended N, errors, NVE drift table.
#include "lammps_fixture.h"
#include "stride_test_util.h"

#include "atom.h"
#include "lammps.h"
#include "library.h"
#include "modify.h"
#include "fix.h"
#include "update.h"

#include <cmath>
#include <cstdio>
#include <cstring>

using namespace kifmm_test;
using stride_test::charged_cube;

namespace {

bool bitwise_equal(const std::map<int, Vec3> &a, const std::map<int, Vec3> &b)
{
  if (a.size() != b.size()) return false;
  for (const auto &[id, v] : a) {
    auto it = b.find(id);
    if (it == b.end() || std::memcmp(v.data(), it->second.data(), sizeof(Vec3)) != 0) return false;
  }
  return true;
}

double max_abs_diff(const std::map<int, Vec3> &a, const std::map<int, Vec3> &b)
{
  double m = 0;
  for (const auto &[id, v] : a)
    for (int d = 0; d < 3; ++d) m = std::max(m, std::fabs(v[d] - b.at(id)[d]));
  return m;
}

class Stride : public LammpsFixture {
 protected:
  // screen output of the statements
  template <typename F> std::string capture(F &&f)
  {
    char *buf = nullptr;
    size_t len = 0;
    FILE *mem = open_memstream(&buf, &len);
    FILE *old = lmp->screen;
    lmp->screen = mem;
    f();
    fflush(mem);
    lmp->screen = old;
    fclose(mem);
    std::string out(buf, len);
    free(buf);
    return out;
  }
  double fv(int k) { return evaluate("f_st[" + std::to_string(k) + "]"); }
};

// ---------------------------------------------------------------- N = 1

struct N1Case {
  const char *name;
  const char *options;
};

class NEqualsOne : public Stride, public ::testing::WithParamInterface<N1Case> {};

TEST_P(NEqualsOne, IsBitForBitTheRunWithoutTheFix)
{
  const std::string soft = "pair_style soft 1.0\npair_coeff * * 20.0";
  auto trajectory = [&](const std::string &fix) {
    create();
    commands(charged_cube(soft, "velocity all create 0.5 777 loop geom", 10));    // 1000 atoms
    if (!fix.empty()) command(fix);
    commands("thermo 1\nrun 40 post no");
    return std::make_tuple(positions_by_id(), forces_by_id(), thermo("elong"), thermo("etotal"));
  };
  auto [x0, f0, e0, t0] = trajectory("");
  auto [x1, f1, e1, t1] = trajectory(std::string("fix st all kifmm/stride 1 ") + GetParam().options);
  EXPECT_TRUE(bitwise_equal(x0, x1)) << "positions differ by up to " << max_abs_diff(x0, x1);
  EXPECT_TRUE(bitwise_equal(f0, f1)) << "forces differ by up to " << max_abs_diff(f0, f1);
  EXPECT_EQ(std::memcmp(&e0, &e1, sizeof(double)), 0) << e0 << " " << e1;
  EXPECT_EQ(std::memcmp(&t0, &t1, sizeof(double)), 0) << t0 << " " << t1;
  EXPECT_EQ(fv(3), 41.0) << "one evaluation per step, setup included";
}

INSTANTIATE_TEST_SUITE_P(Modes, NEqualsOne,
                         ::testing::Values(N1Case{"hold", "mode hold"},
                                           N1Case{"impulse", "mode impulse"},
                                           N1Case{"hold_energy_every", "mode hold energy every"},
                                           N1Case{"impulse_energy_every",
                                                  "mode impulse energy every"}),
                         [](const auto &info) { return std::string(info.param.name); });

// ---------------------------------------------------------------- schedule

TEST_F(Stride, HoldRepeatsTheLastForceAndReportsTheLastEnergy)
{
  // pair zero: the total force is the long-range force
  commands(charged_cube());
  commands("fix st all kifmm/stride 5\nthermo_style custom step elong f_st[2] f_st[3]\n"
           "run 0 post no");
  const auto f0 = forces_by_id();
  const double e0 = thermo("elong");
  command("run 3 post no");
  EXPECT_TRUE(bitwise_equal(forces_by_id(), f0)) << "step 3 must feel the forces of step 0";
  EXPECT_EQ(thermo("elong"), e0) << "energy last";
  EXPECT_EQ(fv(2), 0.0) << "last evaluation step";
  {
    auto *fix = lmp->modify->fix[lmp->modify->find_fix("st")];
    const int i = lmp->atom->map(5);
    EXPECT_EQ(fix->array_atom[i][0], f0.at(5)[0]) << "per-atom output f_st[1]: the cached force";
  }
  command("run 2 post no");
  EXPECT_EQ(fv(2), 5.0);
  EXPECT_GT(max_abs_diff(forces_by_id(), f0), 1e-6) << "step 5 is evaluated afresh";
  EXPECT_NE(thermo("elong"), e0);
  command("run 15 post no");
  // evaluations: setup of run 0, setup of run 3 (step 0 again), 5, setup at 5, 10, 15, 20
  EXPECT_EQ(fv(3), 7.0);
  EXPECT_EQ(fv(2), 20.0);
  EXPECT_EQ(fv(5), 0.0) << "no off-schedule evaluation";
}

TEST_F(Stride, EnergyEveryEvaluatesTheEnergyButKeepsTheHeldForces)
{
  commands(charged_cube());
  commands("fix st all kifmm/stride 5 energy every\nthermo 1\nrun 0 post no");
  const auto f0 = forces_by_id();
  command("run 3 post no");
  EXPECT_TRUE(bitwise_equal(forces_by_id(), f0)) << "forces are still the held ones";
  const double e3 = thermo("elong");
  EXPECT_EQ(fv(4), 3.0) << "energy-only evaluations at steps 1, 2, 3";
  EXPECT_EQ(fv(3), 2.0) << "force evaluations: the setups at step 0 only";
  // the energy of the configuration at step 3, evaluated without the fix
  commands("unfix st\nrun 0 post no");
  EXPECT_NEAR(thermo("elong"), e3, 1e-13 * std::fabs(e3));
}

TEST_F(Stride, ImpulseGivesNTimesTheForceOnEvaluationStepsOnly)
{
  commands(charged_cube());
  command("run 0 post no");
  const auto f0 = forces_by_id();
  commands("fix st all kifmm/stride 5 mode impulse\nrun 0 post no");
  for (const auto &[id, f] : forces_by_id())
    for (int d = 0; d < 3; ++d) ASSERT_EQ(f[d], 5.0 * f0.at(id)[d]) << id;
  command("run 3 post no");
  for (const auto &[id, f] : forces_by_id())
    for (int d = 0; d < 3; ++d) ASSERT_EQ(f[d], 0.0) << id;
  EXPECT_EQ(fv(3), 2.0);
  command("run 2 post no");
  EXPECT_EQ(fv(2), 5.0);
  EXPECT_GT(max_abs_diff(forces_by_id(), f0), 1e-6);
}

TEST_F(Stride, PerAtomEnergyOnASkippedStepIsEvaluatedAndSumsToTheReportedEnergy)
{
  commands(charged_cube());
  commands("fix st all kifmm/stride 5\ncompute pea all pe/atom kspace\n"
           "compute sum all reduce sum c_pea\nthermo_style custom step elong c_sum\n"
           "thermo_modify norm no\nrun 3 post no");
  const double e = thermo("elong"), s = evaluate("c_sum");
  EXPECT_NEAR(s, e, 1e-12 * std::fabs(e));
  EXPECT_GE(fv(4), 1.0) << "the per-atom request forced an energy evaluation";
}

TEST_F(Stride, MinimizationEvaluatesEveryCallWithoutScaling)
{
  commands(charged_cube());
  command("run 0 post no");
  const auto f0 = forces_by_id();
  commands("fix st all kifmm/stride 5 mode impulse\nminimize 0 0 0 0");
  EXPECT_LT(max_abs_diff(forces_by_id(), f0), 1e-12) << "no N-fold impulse in minimization";
}

// ---------------------------------------------------------------- restart

class Restart : public Stride, public ::testing::WithParamInterface<const char *> {};

TEST_P(Restart, SplitRunContinuesTheScheduleExactly)
{
  const std::string soft = "pair_style soft 1.0\npair_coeff * * 20.0";
  const std::string fix = std::string("fix st all kifmm/stride 5 mode ") + GetParam();
  const std::string file = testing::TempDir() + "stride_" + GetParam() + ".restart";
  // 1000 atoms: several octree leaves, so that the far field takes part. Equality is to
  // roundoff: the setup of the second run rebuilds the neighbor lists and (with sorting) the
  // atom order, which changes the order of the pair and FMM sums (differences ~1e-17 seen,
  // none with 125 atoms); the control without the cached forces differs by > 1e-9.
  const std::string in = charged_cube(soft, "velocity all create 0.5 777 loop geom", 10) +
      "atom_modify sort 0 0.0\n";
  // unsplit
  commands(in);
  commands(fix + "\nrun 40 post no");
  const auto x_ref = positions_by_id();
  const double evals_ref = fv(3);

  // same instance, two runs
  create();
  commands(in);
  commands(fix + "\nrun 23 post no\nrun 17 post no");
  EXPECT_LT(max_abs_diff(positions_by_id(), x_ref), 1e-13) << "run 23 + run 17";

  // through a restart file written at step 23 (not a multiple of 5)
  create();
  commands(in);
  commands(fix + "\nrun 23 post no\nwrite_restart " + file);
  auto restarted = [&](const std::string &fixline) {
    create();
    commands("read_restart " + file + "\n" + soft +
             "\nkspace_style kifmm 1e-6\nkspace_modify kifmm tune no\nfix nve all nve\nthermo_modify norm no\n"
             "atom_modify sort 0 0.0\n" + fixline +
             "\nrun 17 post no");
    return positions_by_id();
  };
  const auto x_split = restarted(fix);
  EXPECT_LT(max_abs_diff(x_split, x_ref), 1e-13) << "restart";
  EXPECT_EQ(fv(2), 40.0);
  if (std::string(GetParam()) == "hold")
    EXPECT_EQ(fv(3), evals_ref) << "no evaluation at the setup of step 23";
  EXPECT_EQ(fv(5), 0.0);

  // control: a fix of another ID gets nothing from the file and so must differ (hold)
  if (std::string(GetParam()) == "hold") {
    const auto x_fresh = restarted("fix other all kifmm/stride 5");
    EXPECT_GT(max_abs_diff(x_fresh, x_ref), 1e-9) << "the test must see a missing cache";
  }
  std::remove(file.c_str());
}

INSTANTIATE_TEST_SUITE_P(Modes, Restart, ::testing::Values("hold", "impulse"));

// ---------------------------------------------------------------- cache follows the atoms

TEST_F(Stride, CacheSurvivesSortDeletionAndInsertion)
{
  commands(charged_cube());
  commands("atom_modify sort 1 0.5\nneigh_modify every 1 delay 0 check no\n"
           "fix st all kifmm/stride 10\nrun 0 post no");
  const auto f0 = forces_by_id();
  command("run 3 post no");    // sorted and reneighbored on every step
  EXPECT_TRUE(bitwise_equal(forces_by_id(), f0));

  // deletion: the survivors keep their held forces (which still include the deleted charges)
  commands("group gone id 1:20\ndelete_atoms group gone compress no\nrun 2 post no");
  auto f5 = forces_by_id();
  EXPECT_EQ(natoms(), 105);
  for (const auto &[id, f] : f5)
    for (int d = 0; d < 3; ++d) ASSERT_EQ(f[d], f0.at(id)[d]) << id;
  EXPECT_EQ(fv(5), 0.0);

  // an uncharged atom inserted: no evaluation needed
  commands("create_atoms 1 single 2.0 2.0 6.0 units box\nset atom 126 charge 0.0\nrun 1 post no");
  EXPECT_EQ(fv(5), 0.0);
  EXPECT_EQ(fv(2), 0.0);
  // a charged atom inserted: evaluated at the next setup, off the schedule
  commands("create_atoms 1 single 2.0 6.0 2.0 units box\nset atom 127 charge 1.0\nrun 1 post no");
  EXPECT_EQ(fv(5), 1.0);
  EXPECT_EQ(fv(2), 6.0);
  auto f7 = forces_by_id();
  EXPECT_GT(std::fabs(f7.at(127)[1]), 0.01) << "the new charge feels the others";
  EXPECT_EQ(f7.at(126)[0], 0.0);
  EXPECT_GT(std::fabs(f7.at(50)[0] - f0.at(50)[0]), 1e-6) << "the others were re-evaluated";
}

// ---------------------------------------------------------------- clumps

class Clump : public Stride {
 protected:
  void build(const std::string &fix_before, const std::string &fix_after)
  {
    create();
    commands(R"(
      units lj
      atom_style full
      boundary f f f
      atom_modify map array
      region box block -10 10 -10 10 -10 10 units box
      create_box 1 box
      create_atoms 1 single 0.0 0.0 0.0 units box
      create_atoms 1 single 0.6 0.0 0.0 units box
      create_atoms 1 single 0.3 0.5 0.0 units box
      create_atoms 1 single 0.3 0.2 0.5 units box
      create_atoms 1 single 2.5 1.5 -0.5 units box
      create_atoms 1 single -1.5 2.0 1.0 units box
      create_atoms 1 single 1.0 -2.0 0.5 units box
      mass 1 1.0
      set atom 1*4 mol 1
      set atom 1 charge 1.0
      set atom 2 charge -0.5
      set atom 3 charge 0.7
      set atom 4 charge -1.2
      set atom 5 charge -2.0
      set atom 6 charge 1.5
      set atom 7 charge -1.0
      group clump molecule 1
      pair_style zero 1.0
      pair_coeff * *
      kspace_style kifmm 1e-8
      timestep 0.005
      velocity clump set 0.3 -0.2 0.1
    )");
    if (!fix_before.empty()) command(fix_before);
    command("fix rig clump rigid/small molecule");
    if (!fix_after.empty()) command(fix_after);
    command("compute rl clump rigid/local rig x y z tqx tqy tqz");
  }
  // xcm and torque of the clump
  std::array<double, 6> body()
  {
    auto **a = (double **) lammps_extract_compute(lmp, "rl", LMP_STYLE_LOCAL, LMP_TYPE_ARRAY);
    return {a[0][0], a[0][1], a[0][2], a[0][3], a[0][4], a[0][5]};
  }
};

double norm3(double a, double b, double c)
{
  return std::sqrt(a * a + b * b + c * c);
}

TEST_F(Clump, ReceivesTorqueFromHeldForcesOnSkippedSteps)
{
  // reference: long-range forces evaluated on every step
  build("", "");
  command("run 1 post no");
  const auto t_ref = body();
  const double tref = norm3(t_ref[3], t_ref[4], t_ref[5]);
  ASSERT_GT(tref, 1e-3) << "the clump must feel a torque";

  for (int order = 0; order < 2; ++order) {
    const std::string fix = "fix st all kifmm/stride 5";
    build(order == 0 ? fix : "", order == 0 ? "" : fix);
    command("run 0 post no");
    const auto f0 = forces_by_id();
    command("run 1 post no");    // step 1: skipped, held forces of step 0
    const auto f1 = forces_by_id();
    const auto x1 = positions_by_id();
    const auto b = body();
    for (int id = 1; id <= 4; ++id)
      for (int d = 0; d < 3; ++d) ASSERT_EQ(f1.at(id)[d], f0.at(id)[d]) << "held force " << id;
    // torque the body got = sum (x_i - xcm) x F_i(step 0)
    double t[3] = {0, 0, 0};
    for (int id = 1; id <= 4; ++id) {
      const double dx = x1.at(id)[0] - b[0], dy = x1.at(id)[1] - b[1], dz = x1.at(id)[2] - b[2];
      const auto &f = f0.at(id);
      t[0] += dy * f[2] - dz * f[1];
      t[1] += dz * f[0] - dx * f[2];
      t[2] += dx * f[1] - dy * f[0];
    }
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(b[3 + d], t[d], 1e-12 * tref) << "fix order " << order << " component " << d;
    // close to the every-step torque (positions barely changed), but not identical
    const double diff = norm3(b[3] - t_ref[3], b[4] - t_ref[4], b[5] - t_ref[5]);
    EXPECT_LT(diff, 1e-2 * tref) << "order " << order;
    EXPECT_GT(diff, 0.0) << "held, not fresh";
  }
}

TEST_F(Clump, ImpulseGivesNTimesTheTorqueThenNone)
{
  build("", "");
  command("run 0 post no");
  const auto t0 = body();
  build("", "fix st all kifmm/stride 4 mode impulse");
  command("run 0 post no");
  const auto ti = body();
  for (int d = 3; d < 6; ++d) EXPECT_NEAR(ti[d], 4.0 * t0[d], 1e-12 * std::fabs(4.0 * t0[d]) + 1e-300);
  command("run 1 post no");
  const auto t1 = body();
  for (int d = 3; d < 6; ++d) EXPECT_EQ(t1[d], 0.0);
}

// ---------------------------------------------------------------- choosing N

TEST_F(Stride, StiffnessOfTwoSeparatingChargesAndTheRecommendation)
{
  // +1 and -1 at distance 2 moving apart: per-atom stiffness |dF|/|dx| -> 4 q^2 / r^3 = 0.5
  commands(R"(
    units lj
    atom_style charge
    boundary f f f
    region box block -10 10 -10 10 -10 10 units box
    create_box 1 box
    create_atoms 1 single -1.0 0 0 units box
    create_atoms 1 single 1.0 0 0 units box
    mass 1 1.0
    set atom 1 charge 1.0
    set atom 2 charge -1.0
    velocity all set 0 0 0
    set atom 1 vx -0.001
    set atom 2 vx 0.001
    pair_style zero 1.0
    pair_coeff * *
    kspace_style kifmm 1e-10
    fix nve all nve
    fix st all kifmm/stride 20 kdem 20.0
    timestep 0.01
  )");
  std::string out = capture([&] { command("run 20 post no"); });
  const double k = fv(6);
  EXPECT_NEAR(k, 0.5, 0.01) << out;
  EXPECT_NEAR(fv(7), 20.0, 0.0);
  EXPECT_NEAR(fv(8), std::sqrt(20.0 / k), 1e-12);
  EXPECT_NE(out.find("recommended N <= S = sqrt(k_DEM/k_LR) = 6.3"), std::string::npos) << out;
  EXPECT_NE(out.find("WARNING: fix kifmm/stride: N = 20 exceeds the recommended S"),
            std::string::npos)
      << out;
}

TEST_F(Stride, AutoChoosesNFromTheProbe)
{
  commands(charged_cube("pair_style soft 1.0\npair_coeff * * 20.0"));
  commands("fix st all kifmm/stride auto kdem 200.0 nmax 8\nrun 40 post no");
  const double s = fv(8);
  ASSERT_GT(s, 0.0);
  const int expect = std::max(1, std::min(8, (int) std::floor(s)));
  EXPECT_EQ(fv(1), expect) << "S = " << s;
  printf("  auto: k_LR = %.4g, S = %.3g, N = %g\n", fv(6), s, fv(1));
}

TEST_F(Stride, NLongerThanTheRunIsAWarning)
{
  commands(charged_cube());
  auto count = [](const std::string &out) {
    std::size_t n = 0;
    for (std::size_t at = out.find("WARNING: fix kifmm/stride: N = "); at != std::string::npos;
         at = out.find("WARNING: fix kifmm/stride: N = ", at + 1))
      ++n;
    return n;
  };
  command("fix st all kifmm/stride 1000000");
  std::string out = capture([&] { command("run 100 post no"); });
  EXPECT_EQ(count(out), 1u) << out;
  EXPECT_NE(out.find("WARNING: fix kifmm/stride: N = 1000000 is longer than this run of 100 steps "
                     "(steps 0 to 100): the long-range forces are not evaluated again during the "
                     "run (the forces of step 0 are held throughout)"),
            std::string::npos)
      << out;
  out = capture([&] { command("run 0 post no"); });
  EXPECT_EQ(count(out), 0u) << out;
  // steps 100 to 200 hold the multiple 150; 200 to 300 hold 300; 300 to 340 none
  commands("unfix st\nfix st all kifmm/stride 150");
  out = capture([&] { commands("run 100 post no\nrun 100 post no"); });
  EXPECT_EQ(count(out), 0u) << out;
  out = capture([&] { command("run 40 post no"); });
  EXPECT_EQ(count(out), 1u) << out;
  EXPECT_NE(out.find("N = 150 is longer than this run of 40 steps (steps 300 to 340)"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("(the forces of step 300 are held throughout)"), std::string::npos) << out;
  commands("unfix st\nfix st all kifmm/stride 1000 mode impulse");
  out = capture([&] { command("run 20 post no"); });
  EXPECT_NE(out.find("N = 1000 is longer than this run of 20 steps (steps 340 to 360): the "
                     "long-range forces are not evaluated again during the run (mode impulse: no "
                     "long-range force)"),
            std::string::npos)
      << out;
  // auto chooses N itself
  commands("unfix st\nfix st all kifmm/stride auto kdem 200.0");
  out = capture([&] { command("run 20 post no"); });
  EXPECT_EQ(count(out), 0u) << out;
}

// ---------------------------------------------------------------- errors

TEST_F(Stride, ErrorsNameTheProblem)
{
  commands(charged_cube());
  EXPECT_LAMMPS_ERROR(command("fix st all kifmm/stride 0"), "N = 0 must be a positive integer");
  EXPECT_LAMMPS_ERROR(command("fix st all kifmm/stride 5 mode sometimes"),
                      "mode must be hold or impulse");
  EXPECT_LAMMPS_ERROR(command("fix st all kifmm/stride 5 energy never"),
                      "energy must be last or every");
  EXPECT_LAMMPS_ERROR(command("fix st all kifmm/stride 5 colour red"), "unknown keyword 'colour'");
  commands("group some id 1:10");
  EXPECT_LAMMPS_ERROR(command("fix st some kifmm/stride 5"), "must use group all");
  EXPECT_LAMMPS_ERROR(commands("fix st all kifmm/stride auto\nrun 0"),
                      "auto needs the contact stiffness: add kdem");
  EXPECT_LAMMPS_ERROR(commands("kspace_style none\nfix st all kifmm/stride 5\nrun 0"),
                      "requires kspace_style kifmm");
  EXPECT_LAMMPS_ERROR(commands("fix st all kifmm/stride 5\nfix st2 all kifmm/stride 5\nrun 0"),
                      "Only one fix kifmm/stride");
}

// ---------------------------------------------------------------- NVE drift

TEST_F(Stride, NVEDriftIsBoundedAndGrowsWithN)
{
  // charged spheres with purely repulsive (WCA) contacts, sigma 0.8, around a rock-salt
  // cluster; energy every, so that etotal is exact on every output
  struct Drift {
    double rel, per_atom, s;
  };
  auto drift = [&](int n, const char *mode) {
    create();
    std::string in = charged_cube(
        "pair_style lj/cut 0.898\npair_coeff * * 1.0 0.8\npair_modify shift yes",
        "velocity all create 0.2 777 loop geom");
    in.replace(in.find("boundary f f f"), 14, "boundary s s s");
    commands(in);
    // kdem: the WCA curvature at a typical contact distance 0.85, E'' ~ 255
    command("fix st all kifmm/stride " + std::to_string(n) + " mode " + mode +
            " energy every kdem 255");
    commands("timestep 0.005\nthermo 50\nrun 0 post no");
    const double e0 = thermo("etotal"), k0 = thermo("ke");
    double maxdev = 0;
    for (int k = 0; k < 20; ++k) {
      command("run 100 post no");
      maxdev = std::max(maxdev, std::fabs(thermo("etotal") - e0));
    }
    return Drift{maxdev / k0, maxdev / natoms(), fv(8)};
  };
  const int ns[] = {1, 5, 10, 20};
  Drift d[2][4];
  printf("  NVE 2000 steps, dt 0.005, 125 charges: max |E - E0| / KE0  (per atom)\n"
         "  N   hold                  impulse               S\n");
  for (int k = 0; k < 4; ++k) {
    d[0][k] = drift(ns[k], "hold");
    d[1][k] = drift(ns[k], "impulse");
    printf("  %-3d %.3e (%.2e)  %.3e (%.2e)  %.3g\n", ns[k], d[0][k].rel, d[0][k].per_atom,
           d[1][k].rel, d[1][k].per_atom, d[0][k].s);
  }
  const double bound[2] = {0.5, 0.01};    // hold is first order (lagged force), impulse symplectic
  for (int m = 0; m < 2; ++m) {
    for (int k = 0; k < 4; ++k)
      EXPECT_LT(d[m][k].rel, bound[m]) << "bounded: mode " << m << " N " << ns[k];
    EXPECT_GT(d[m][3].rel, d[m][1].rel) << "N 20 drifts more than N 5, mode " << m;
    EXPECT_GT(d[m][1].rel, d[m][0].rel) << "N 5 drifts more than N 1, mode " << m;
  }
  EXPECT_GT(d[0][3].rel, d[1][3].rel) << "impulse conserves energy better than hold";
}

}    // namespace
