// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix kifmm/stride on 2 MPI ranks: the held forces move with their atoms across the processor
// boundary (exchange, sort, reneighboring on every step), the trajectory equals the serial
// one, and a restart split on 2 ranks equals the unsplit run. Run with mpirun -np 2.
#include "lammps_fixture.h"
#include "stride_test_util.h"

#include "atom.h"
#include "lammps.h"

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <mpi.h>

using namespace kifmm_test;
using stride_test::charged_cube;

namespace {

double max_abs_diff(const std::map<int, Vec3> &a, const std::map<int, Vec3> &b)
{
  double m = 0;
  for (const auto &[id, v] : a)
    for (int d = 0; d < 3; ++d) m = std::max(m, std::fabs(v[d] - b.at(id)[d]));
  return m;
}

// atoms moving +x at 8 units/time, dt 0.05: 0.4 per step across the rank boundary at x = 2
std::string moving_cube(bool two_ranks)
{
  std::string in = two_ranks ? "processors 2 1 1\n" : "";
  in += charged_cube("pair_style zero 1.0\npair_coeff * *", "velocity all set 8.0 0 0");
  in += "timestep 0.05\natom_modify sort 1 0.5\nneigh_modify every 1 delay 0 check no\n";
  return in;
}

class StrideMPI : public LammpsFixture {
 protected:
  int me = 0, nprocs = 1;
  void SetUp() override
  {
    LammpsFixture::SetUp();
    MPI_Comm_rank(MPI_COMM_WORLD, &me);
    MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  }
  std::map<int, int> owners()
  {
    std::vector<double> mine;    // (atom ID, rank) rows
    for (int i = 0; i < lmp->atom->nlocal; ++i) mine.insert(mine.end(), {(double) lmp->atom->tag[i], (double) me});
    const std::vector<double> all = kifmm_test::gather_rows(lmp, mine, 2);
    std::map<int, int> out;
    for (std::size_t k = 0; k + 2 <= all.size(); k += 2) out[(int) all[k]] = (int) all[k + 1];
    return out;
  }
  double fv(int k) { return evaluate("f_st[" + std::to_string(k) + "]"); }
};

TEST_F(StrideMPI, HeldForcesFollowTheirAtomsAcrossRanks)
{
  ASSERT_EQ(nprocs, 2) << "run under mpirun -np 2";
  commands(moving_cube(true));
  // atom IDs of create_atoms depend on the rank grid: the serial reference reads this file
  const std::string data = testing::TempDir() + "stride_mpi_start.data";
  command("write_data " + data + " nocoeff");
  commands("fix st all kifmm/stride 5\nrun 0 post no");
  const auto f0 = forces_by_id();
  const auto own0 = owners();
  int nlocal0 = lmp->atom->nlocal;
  command("run 4 post no");    // steps 1-4: held forces of step 0
  const auto f4 = forces_by_id();
  const auto own4 = owners();
  int moved = 0;
  for (const auto &[id, p] : own0)
    if (own4.at(id) != p) ++moved;
  EXPECT_GT(moved, 10) << "atoms must change rank";
  EXPECT_GT(nlocal0, 0);
  for (const auto &[id, f] : f4)
    for (int d = 0; d < 3; ++d)
      ASSERT_EQ(f[d], f0.at(id)[d]) << "atom " << id << " (moved ranks: "
                                    << (own4.at(id) != own0.at(id)) << ")";
  command("run 8 post no");
  EXPECT_EQ(fv(2), 10.0);
  const auto x2 = positions_by_id();
  if (me == 0) printf("  %d of 125 atoms changed rank in 4 steps\n", moved);

  // serial reference of the same 12 steps on rank 0
  double diff = 0.0;
  if (me == 0) {
    LAMMPS_NS::LAMMPS *ref = kifmm_test::open_lammps(MPI_COMM_SELF);
    LAMMPS_NS::LAMMPS *saved = lmp;
    lmp = ref;
    commands("units lj\natom_style charge\nboundary f f f\natom_modify map array\n"
             "read_data " + data + "\npair_style zero 1.0\npair_coeff * *\n"
             "kspace_style kifmm 1e-6\nfix nve all nve\ntimestep 0.05\natom_modify sort 1 0.5\n"
             "neigh_modify every 1 delay 0 check no\n"
             "fix st all kifmm/stride 5\nrun 0 post no\nrun 4 post no\nrun 8 post no");
    const std::map<int, Vec3> xs = kifmm_test::positions_by_id(ref);
    lmp = saved;
    delete ref;
    diff = max_abs_diff(xs, x2);
    std::remove(data.c_str());
    printf("  2 ranks vs serial: max position difference %.3e\n", diff);
  }
  MPI_Bcast(&diff, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  EXPECT_LT(diff, 1e-10);
}

TEST_F(StrideMPI, RestartSplitOnTwoRanksEqualsTheUnsplitRun)
{
  ASSERT_EQ(nprocs, 2) << "run under mpirun -np 2";
  const std::string file = testing::TempDir() + "stride_mpi.restart";
  const std::string fix = "fix st all kifmm/stride 5";
  commands(moving_cube(true));
  commands(fix + "\nrun 12 post no");
  const auto x_ref = positions_by_id();

  create();
  commands(moving_cube(true));
  commands(fix + "\nrun 7 post no\nwrite_restart " + file);
  auto restarted = [&](const std::string &fixline) {
    create();
    commands("read_restart " + file +
             "\npair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-6\nfix nve all nve\n"
             "atom_modify sort 1 0.5\nneigh_modify every 1 delay 0 check no\n" +
             fixline + "\nrun 5 post no");
    return positions_by_id();
  };
  const double d = max_abs_diff(restarted(fix), x_ref);
  EXPECT_LT(d, 1e-12) << "restart split on 2 ranks";
  EXPECT_EQ(fv(2), 10.0);
  const double control = max_abs_diff(restarted("fix other all kifmm/stride 5"), x_ref);
  EXPECT_GT(control, 1e-9) << "without the cached forces the run must differ";
  if (me == 0) {
    printf("  restart split: %.3e, without cache: %.3e\n", d, control);
    std::remove(file.c_str());
  }
}

}    // namespace
