// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix clump/rigid in parallel equals serial: the same granular system of clumps (pair
// gran/hooke/history between clumps, a damped granular wall, a uniform field on charged
// pebbles, clumps straddling the processor boundary) is run on MPI_COMM_WORLD and, on every
// rank, on MPI_COMM_SELF; clump positions, orientations and velocities must agree.
// Registered to run under mpirun -np 2 (label mpi); also passes on one rank.
#include "clump_test_util.h"

#include "compute.h"
#include "input.h"
#include "modify.h"
#include "lammps.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

using namespace clump_test;
using LAMMPS_NS::LAMMPS;

namespace {

std::string system_script(const std::string &dimer_file, const std::string &asym_file)
{
  std::ostringstream s;
  s << R"(
units si
atom_style hybrid sphere charge
atom_modify map array
boundary p p f
fix prop all property/atom mol ghost yes
region box block -0.2 0.2 -0.05 0.05 -0.05 0.05
create_box 2 box
mass * 1.0
comm_modify cutoff 0.04 vel yes
neighbor 0.002 bin
thermo_style custom step
)";
  s << clump_row_commands(dimer_file, asym_file);
  s << R"(
pair_style gran/hooke/history 200.0 NULL 30.0 NULL 0.5 1
pair_coeff * *
timestep 2e-5
fix wall all wall/gran hooke 200.0 NULL 30.0 NULL 0.5 1 zplane -0.05 NULL
fix ef all efield 2.0e-3 0.0 -1.0e-3
variable vx atom 0.3*sin(40*x)+0.1*cos(60*y)
variable vy atom 0.05*cos(30*x)
velocity all set v_vx v_vy -1.0
fix c all clump/rigid density 2500
)";
  return s.str();
}

}    // namespace

TEST(ClumpMpi, ParallelEqualsSerial)
{
  const std::string dimer_file = write_molecule("dimer", dimer());
  const std::string asym_file = write_molecule("asym", asymmetric());
  const std::string script = system_script(dimer_file, asym_file);

  LAMMPS *par = open_lammps(MPI_COMM_WORLD);
  LAMMPS *ser = open_lammps(MPI_COMM_SELF);
  run_lines(par, script);
  run_lines(ser, script);

  int nprocs;
  MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  // clumps are spread over the ranks
  {
    int ic = par->modify->find_compute("c_local");
    ASSERT_GE(ic, 0);
    run_lines(par, "run 0");
    run_lines(ser, "run 0");
    auto *c = par->modify->compute[ic];
    c->compute_local();
    int mine = c->size_local_rows, fewest;
    MPI_Allreduce(&mine, &fewest, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    EXPECT_GT(fewest, 0) << "every rank owns clumps";
  }
  auto r0 = clump_rows(ser, "c");
  ASSERT_EQ(r0.size(), 8u);
  for (int chunk = 0; chunk < 3; ++chunk) {
    run_lines(par, "run 500 post no");
    run_lines(ser, "run 500 post no");
    auto rp = clump_rows(par, "c"), rs = clump_rows(ser, "c");
    ASSERT_EQ(rp.size(), rs.size());
    for (auto &[mol, s] : rs) {
      const auto &p = rp.at(mol);
      SCOPED_TRACE(testing::Message() << "clump " << mol << " after " << 500 * (chunk + 1));
      EXPECT_EQ(p[MASS], s[MASS]);
      for (int k : {XU, YU, ZU}) EXPECT_NEAR(p[k], s[k], 1e-10);
      for (int k : {VX, VY, VZ}) EXPECT_NEAR(p[k], s[k], 1e-8);
      for (int k : {QUATW, QUATI, QUATJ, QUATK}) EXPECT_NEAR(p[k], s[k], 1e-8);
      for (int k : {OMEGAX, OMEGAY, OMEGAZ}) EXPECT_NEAR(p[k], s[k], 1e-5 + 1e-8 * std::fabs(s[k]));
    }
  }
  // the run had contacts and field forces: clumps lost energy to damping, moved, turned
  auto r1 = clump_rows(ser, "c");
  int turned = 0;
  for (auto &[mol, s] : r1) {
    const auto &a = r0.at(mol);
    if (std::fabs(s[QUATW] - a[QUATW]) + std::fabs(s[QUATI] - a[QUATI]) > 1e-3) ++turned;
  }
  EXPECT_GE(turned, 4);
  double vz_up = 0;
  for (auto &[mol, s] : r1) vz_up = std::max(vz_up, s[VZ]);
  EXPECT_GT(vz_up, 0.0) << "some clump bounced off the wall";
  delete ser;
  delete par;
}

// kspace kifmm (with fix kifmm/stride) on clumps: the pairs inside each clump are left out on
// every rank (the clumps' pebbles are gathered by clump ID across ranks, clumps straddle the
// processor boundary); open and periodic boundaries, parallel equals serial.
class ClumpMpiKifmm : public ::testing::TestWithParam<const char *> {};

TEST_P(ClumpMpiKifmm, ParallelEqualsSerial)
{
  const std::string dimer_file = write_molecule("dimer", dimer());
  const std::string asym_file = write_molecule("asym", asymmetric());
  std::string script = system_script(dimer_file, asym_file);
  auto replace = [&](const std::string &from, const std::string &to) {
    const auto at = script.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    script.replace(at, from.size(), to);
  };
  replace("boundary p p f", std::string("boundary ") + GetParam());
  // a cubic box: the periodic octree (elongated boxes take the single-level grid)
  replace("region box block -0.2 0.2 -0.05 0.05 -0.05 0.05", "region box block -0.2 0.2 -0.2 0.2 -0.2 0.2");
  replace("fix wall all wall/gran hooke 200.0 NULL 30.0 NULL 0.5 1 zplane -0.05 NULL\n", "");
  script += "set type 1 charge 0.25\ndielectric 1.0e14\nkspace_style kifmm 1e-8\n"
            "fix st all kifmm/stride 5\nthermo_style custom step elong\nthermo_modify norm no\n";

  LAMMPS *par = open_lammps(MPI_COMM_WORLD);
  LAMMPS *ser = open_lammps(MPI_COMM_SELF);
  run_lines(par, script);
  run_lines(ser, script);
  for (int chunk = 0; chunk < 3; ++chunk) {
    run_lines(par, chunk == 0 ? "run 0 post no" : "run 200 post no");
    run_lines(ser, chunk == 0 ? "run 0 post no" : "run 200 post no");
    auto rp = clump_rows(par, "c"), rs = clump_rows(ser, "c");
    ASSERT_EQ(rs.size(), 8u);
    ASSERT_EQ(rp.size(), rs.size());
    double fscale = 0;
    for (auto &[mol, s] : rs)
      for (int k : {FX, FY, FZ}) fscale = std::max(fscale, std::fabs(s[k]));
    ASSERT_GT(fscale, 0.0);
    for (auto &[mol, s] : rs) {
      const auto &p = rp.at(mol);
      SCOPED_TRACE(testing::Message() << GetParam() << " clump " << mol << " chunk " << chunk);
      for (int k : {XU, YU, ZU}) EXPECT_NEAR(p[k], s[k], 1e-10);
      for (int k : {VX, VY, VZ}) EXPECT_NEAR(p[k], s[k], 1e-8);
      for (int k : {FX, FY, FZ, TQX, TQY, TQZ}) EXPECT_NEAR(p[k], s[k], 1e-8 * fscale);
    }
  }
  delete ser;
  delete par;
}

INSTANTIATE_TEST_SUITE_P(Boundaries, ClumpMpiKifmm, ::testing::Values("f f f", "p p p"),
                         [](const auto &info) { return std::string(info.param[0] == 'f' ? "open" : "periodic"); });
