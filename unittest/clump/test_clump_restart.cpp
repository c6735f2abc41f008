// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix clump/rigid and restart / data files:
//  - a run split by write_restart / read_restart equals the unsplit run: bit for bit on one
//    rank, to 1e-12 on two (registered twice: serial and mpirun -np 2). The system has clumps
//    of three shapes with charged pebbles, kspace kifmm with fix kifmm/stride 5 (the split is
//    not on a multiple of 5: the held forces come from the restart file), granular contacts
//    with a wall (the split falls during them), an electric field; mass properties,
//    positions, orientations and motion of the clumps and every pebble's position and
//    velocity are compared. The contacts are elastic (no damping, no friction): LAMMPS
//    evaluates velocity-dependent forces at the set-up of a run with the full-step velocities
//    of the restart file, not the half-step ones of the unsplit run, which no fix can undo.
//    Also with integrator nve (rigid/nve/small: its conjqm is kept across the set-up) and with
//    the gravity keyword (the clump weight is in the first half-step of the restarted run).
//  - control: re-specifying the fix under another ID (the stored state is not used) gives a
//    different run, so the comparison can fail;
//  - a changed density after read_restart: warning, stored state not used;
//  - write_data: warning and a comment in the data file; after read_data the re-specified
//    fix recovers the clumps (count, union mass to the integration accuracy, motion).
#include "clump_test_util.h"

#include "atom.h"
#include "input.h"
#include "lammps.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

using namespace clump_test;
using LAMMPS_NS::LAMMPS;

namespace {

int world_rank()
{
  int me;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  return me;
}

int world_size()
{
  int n;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

// file names shared by the ranks of MPI_COMM_WORLD (rank 0's scratch directory)
std::string shared_name(const std::string &name)
{
  std::string dir = scratch_dir().string();
  int len = (int) dir.size();
  MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
  dir.resize(len);
  MPI_Bcast(&dir[0], len, MPI_CHAR, 0, MPI_COMM_WORLD);
  return dir + "/" + name;
}

// styles that restart files do not keep (re-specified after read_restart); tune no: the runs
// are compared bit for bit, so the modelled tree, not a timed one
const char *const FORCES = R"(
neigh_modify every 1 delay 0 check no
fix wall all wall/gran hooke 200.0 NULL 0.0 NULL 0.5 1 zplane -0.05 NULL
fix ef all efield 2.0e-3 0.0 -1.0e-3
fix grav nothing gravity 9.81 vector 0 0 -1
dielectric 1.0e14
kspace_style kifmm 1e-6
kspace_modify kifmm tune no
fix st all kifmm/stride 5
thermo_style custom step
)";

std::string system_script(const std::string &dimer_file, const std::string &asym_file,
                          const std::string &fix_args = "density 2500")
{
  std::ostringstream s;
  s << R"(
units si
atom_style hybrid sphere charge
atom_modify map array sort 0 0.0
boundary f f f
fix prop all property/atom mol ghost yes
region box block -0.2 0.2 -0.1 0.1 -0.1 0.1
create_box 2 box
mass * 1.0
comm_modify cutoff 0.04 vel yes
neighbor 0.002 bin
timestep 1e-4
group nothing empty
)";
  s << clump_row_commands(dimer_file, asym_file);
  // the dimers and the asymmetric clumps get charges too
  s << R"(
set type 1 charge 0.25
pair_style gran/hooke 200.0 NULL 0.0 NULL 0.5 1
pair_coeff * *
variable vx atom 0.3*sin(40*x)+0.1*cos(60*y)
variable vy atom 0.05*cos(30*x)
velocity all set v_vx v_vy -1.0
)";
  s << FORCES << "fix c all clump/rigid " << fix_args << "\n";
  return s.str();
}

// x, v, omega of every atom by ID (all ranks)
std::map<long, std::vector<double>> atoms_by_id(LAMMPS *lmp)
{
  auto *a = lmp->atom;
  std::vector<double> mine;
  for (int i = 0; i < a->nlocal; ++i) {
    mine.push_back((double) a->tag[i]);
    for (int d = 0; d < 3; ++d) mine.push_back(a->x[i][d]);
    for (int d = 0; d < 3; ++d) mine.push_back(a->v[i][d]);
    for (int d = 0; d < 3; ++d) mine.push_back(a->omega[i][d]);
  }
  const std::vector<double> all = kifmm_test::gather_rows(lmp, mine, 10);
  std::map<long, std::vector<double>> out;
  for (std::size_t k = 0; k + 10 <= all.size(); k += 10)
    out[(long) all[k]] = std::vector<double>(all.begin() + k + 1, all.begin() + k + 10);
  return out;
}

struct State {
  std::map<long, std::vector<double>> atoms;
  std::map<int, std::vector<double>> clumps;
};

State state_of(LAMMPS *lmp, const std::string &fix_id = "c")
{
  return {atoms_by_id(lmp), clump_rows(lmp, fix_id)};
}

// largest |a - b| / (1 + |a|) over atoms and clump rows (columns that define the state)
double max_rel_diff(const State &a, const State &b)
{
  double d = 0.0;
  if (a.atoms.size() != b.atoms.size() || a.clumps.size() != b.clumps.size()) return 1e300;
  for (const auto &[id, va] : a.atoms) {
    const auto &vb = b.atoms.at(id);
    for (size_t k = 0; k < va.size(); ++k)
      d = std::max(d, std::fabs(va[k] - vb[k]) / (1.0 + std::fabs(va[k])));
  }
  for (const auto &[mol, ra] : a.clumps) {
    const auto &rb = b.clumps.at(mol);
    for (int k : {MASS, XU, YU, ZU, VX, VY, VZ, FX, FY, FZ, TQX, TQY, TQZ, OMEGAX, OMEGAY, OMEGAZ,
                  ANGMOMX, ANGMOMY, ANGMOMZ, QUATW, QUATI, QUATJ, QUATK, INERTIAX, INERTIAY,
                  INERTIAZ})
      d = std::max(d, std::fabs(ra[k] - rb[k]) / (1.0 + std::fabs(ra[k])));
  }
  return d;
}

bool bitwise_equal(const State &a, const State &b)
{
  if (a.atoms != b.atoms) return false;
  if (a.clumps.size() != b.clumps.size()) return false;
  for (const auto &[mol, ra] : a.clumps) {
    // every column of compute rigid/local but the first: the body ID is the tag of the pebble
    // that rigid/small picks as the clump's owner (the one nearest the centre), picked again
    // from the positions after a restart (the two pebbles of a dimer are a tie)
    const auto &rb = b.clumps.at(mol);
    if (!std::equal(ra.begin() + 1, ra.end(), rb.begin() + 1)) return false;
  }
  return true;
}

class ClumpRestart : public ::testing::Test {
 protected:
  std::string dimer_file, asym_file, script;
  void SetUp() override
  {
    dimer_file = shared_name("dimer.mol");
    asym_file = shared_name("asym.mol");
    if (world_rank() == 0) {
      write_molecule("dimer", dimer());
      write_molecule("asym", asymmetric());
    }
    MPI_Barrier(MPI_COMM_WORLD);
    script = system_script(dimer_file, asym_file);
  }

  // read the restart file and re-specify what it does not keep
  std::string restarted(const std::string &file, const std::string &fix_line)
  {
    return "read_restart " + file + "\nfix prop all property/atom mol ghost yes\n" + FORCES +
        fix_line + "\n";
  }
};

class ClumpRestartSplit : public ClumpRestart,
                          public ::testing::WithParamInterface<const char *> {};

TEST_P(ClumpRestartSplit, SplitRunEqualsTheUnsplitRun)
{
  const int nprocs = world_size();
  const std::string file = shared_name("split.restart");
  const std::string fix_args = GetParam();
  script = system_script(dimer_file, asym_file, fix_args);

  LAMMPS *lmp = open_lammps(MPI_COMM_WORLD);
  run_lines(lmp, script + "run 300 post no");
  const State unsplit = state_of(lmp);
  delete lmp;

  lmp = open_lammps(MPI_COMM_WORLD);
  run_lines(lmp, script + "run 137 post no\nwrite_restart " + file);
  const State before = state_of(lmp);
  delete lmp;

  // mass properties and state survive the restart file (checked after run 0)
  lmp = open_lammps(MPI_COMM_WORLD);
  run_lines(lmp, restarted(file, "fix c all clump/rigid " + fix_args) + "run 0 post no");
  const State at_restart = state_of(lmp);
  delete lmp;
  ASSERT_EQ(at_restart.clumps.size(), 8u);
  for (const auto &[mol, r] : before.clumps) {
    const auto &s = at_restart.clumps.at(mol);
    SCOPED_TRACE(testing::Message() << "clump " << mol);
    EXPECT_EQ(s[MASS], r[MASS]);
    for (int k : {INERTIAX, INERTIAY, INERTIAZ, QUATW, QUATI, QUATJ, QUATK, XU, YU, ZU, VX, VY,
                  VZ, ANGMOMX, ANGMOMY, ANGMOMZ})
      EXPECT_EQ(s[k], r[k]) << "column " << k;
  }

  lmp = open_lammps(MPI_COMM_WORLD);
  run_lines(lmp, restarted(file, "fix c all clump/rigid " + fix_args) + "run 163 post no");
  const State split = state_of(lmp);
  delete lmp;

  // control: the fix under another ID does not take the stored state
  lmp = open_lammps(MPI_COMM_WORLD);
  run_lines(lmp, restarted(file, "fix c2 all clump/rigid " + fix_args) + "run 163 post no");
  const State control = state_of(lmp, "c2");
  delete lmp;

  // the restart falls during wall contacts: some pebble (radius >= 0.004) overlaps the wall
  double zmin = 1e300;
  for (const auto &[id, v] : before.atoms) zmin = std::min(zmin, v[2]);
  EXPECT_LT(zmin, -0.05 + 0.004) << "no pebble touches the wall at the split";
  // the run had contacts with the wall: they slowed clumps that came at it with vz = -1
  double vz_max = -1e300;
  for (const auto &[mol, r] : unsplit.clumps) vz_max = std::max(vz_max, r[VZ]);
  EXPECT_GT(vz_max, -0.5) << "some clump was slowed down by the wall";

  // control: compare the pebbles only (a recomputed clump may get other principal axes, i.e.
  // another quaternion, for the same orientation)
  const State unsplit_atoms{unsplit.atoms, {}}, control_atoms{control.atoms, {}};
  const double dr = max_rel_diff(before, at_restart);
  const double d = max_rel_diff(unsplit, split), dc = max_rel_diff(unsplit_atoms, control_atoms);
  if (world_rank() == 0)
    std::printf("  %s, %d rank(s): split vs unsplit %.3g (relative), without the stored state %.3g "
                "(split vs the run up to the restart: %.3g)\n",
                fix_args.c_str(), nprocs, d, dc, dr);
  if (nprocs == 1) {
    EXPECT_TRUE(bitwise_equal(unsplit, split)) << "largest relative difference " << d;
  } else {
    EXPECT_LT(d, 1e-12);
  }
  EXPECT_GT(dc, 1e-13) << "without the stored state the run must differ";
}

INSTANTIATE_TEST_SUITE_P(Integrators, ClumpRestartSplit,
                         ::testing::Values("density 2500", "density 2500 integrator nve",
                                           "density 2500 gravity grav"));

TEST_F(ClumpRestart, ChangedDensityRecomputesWithAWarning)
{
  const std::string file = shared_name("density.restart");
  const std::string log = shared_name("density.log");
  LAMMPS *lmp = open_lammps(MPI_COMM_WORLD);
  run_lines(lmp, script + "run 10 post no\nwrite_restart " + file);
  const State before = state_of(lmp);
  delete lmp;
  lmp = open_lammps(MPI_COMM_WORLD, {"-log", log});
  run_lines(lmp, restarted(file, "fix c all clump/rigid density 5000") + "run 0 post no");
  const State after = state_of(lmp);
  delete lmp;
  for (const auto &[mol, r] : before.clumps)
    EXPECT_NEAR(after.clumps.at(mol)[MASS] / r[MASS], 2.0, 2e-6) << "clump " << mol;
  if (world_rank() == 0) {
    std::ifstream f(log);
    std::stringstream text;
    text << f.rdbuf();
    EXPECT_NE(text.str().find("WARNING: Fix clump/rigid c: the restart file holds clumps of "
                              "density 2500, the fix now asks for density 5000"),
              std::string::npos)
        << text.str();
  }
}

TEST_F(ClumpRestart, WriteDataWarnsAndReadDataRecoversTheClumps)
{
  const std::string data = shared_name("clumps.data");
  const std::string log = shared_name("write_data.log");
  LAMMPS *lmp = open_lammps(MPI_COMM_WORLD, {"-log", log});
  run_lines(lmp, script + "run 30 post no\nwrite_data " + data);
  const State before = state_of(lmp);
  delete lmp;
  if (world_rank() == 0) {
    std::ifstream f(log);
    std::stringstream text;
    text << f.rdbuf();
    EXPECT_NE(text.str().find("WARNING: Fix clump/rigid c: write_data stores the pebbles and "
                              "their molecule IDs, not the clump state"),
              std::string::npos);
    std::ifstream d(data);
    std::stringstream dtext;
    dtext << d.rdbuf();
    EXPECT_NE(dtext.str().find("# fix clump/rigid c: clumps are the molecules of group all"),
              std::string::npos);
  }

  lmp = open_lammps(MPI_COMM_WORLD);
  run_lines(lmp, R"(
units si
atom_style hybrid sphere charge
atom_modify map array sort 0 0.0
boundary f f f
fix prop all property/atom mol ghost yes
comm_modify cutoff 0.04 vel yes
neighbor 0.002 bin
timestep 1e-4
read_data )" + data + R"( fix prop NULL Molecules
group nothing empty
)" + FORCES + "fix c all clump/rigid density 2500\nrun 0 post no");
  const State after = state_of(lmp);
  delete lmp;
  ASSERT_EQ(after.clumps.size(), 8u);
  for (const auto &[mol, r] : before.clumps) {
    const auto &s = after.clumps.at(mol);
    SCOPED_TRACE(testing::Message() << "clump " << mol);
    // union mass recomputed for the rotated clump: equal to the integration accuracy (tol 1e-5)
    EXPECT_NEAR(s[MASS] / r[MASS], 1.0, 1e-6);
    for (int k : {XU, YU, ZU}) EXPECT_NEAR(s[k], r[k], 1e-9);
    for (int k : {VX, VY, VZ}) EXPECT_NEAR(s[k], r[k], 1e-9);
    // L = I omega with the recomputed inertia: equal to the integration accuracy (tol 1e-5)
    for (int k : {ANGMOMX, ANGMOMY, ANGMOMZ})
      EXPECT_NEAR(s[k], r[k], 1e-5 * std::fabs(r[k]) + 1e-15);
  }
}

}    // namespace
