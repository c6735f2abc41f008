// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "kifmm_timing.h"

#include "kifmm.h"
#include "kspace_kifmm.h"

#include "comm.h"
#include "error.h"
#include "force.h"
#include "utils.h"

#include <algorithm>
#include <mpi.h>

using namespace LAMMPS_NS;

void KIFMMTiming::add(const kifmm::Stats &s, double comm, double total, std::size_t targets,
                      std::size_t bytes_sent, double polarize)
{
  bytes += (double) bytes_sent;
  const double engine[] = {s.t_tree, s.t_lists, s.t_upward, s.t_m2l, s.t_wx, s.t_downward, s.t_p2p};
  double used = comm + polarize;
  t[Polarize] += polarize;
  for (int k = 0; k < 7; ++k) {
    t[k] += engine[k];
    used += engine[k];
  }
  t[Comm] += comm;
  t[Other] += std::max(0.0, total - used);
  ++evaluations;
  points += (double) targets;
}

FixKIFMMTiming::FixKIFMMTiming(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  if (narg != 3) error->all(FLERR, "Illegal internal fix KIFMM/TIMING command");
}

void FixKIFMMTiming::post_run()
{
  auto *kspace = dynamic_cast<KSpaceKIFMM *>(force->kspace);
  if (kspace) print_kifmm_timing(lmp, kspace->timing());
}

void LAMMPS_NS::print_kifmm_timing(LAMMPS *lmp, const KIFMMTiming &timing)
{
  MPI_Comm world = lmp->world;
  int nprocs = 1;
  MPI_Comm_size(world, &nprocs);
  const int n = KIFMMTiming::NPHASES + 2;
  double mine[n], lo[n], hi[n], sum[n];
  for (int k = 0; k < KIFMMTiming::NPHASES; ++k) mine[k] = timing.t[k];
  mine[KIFMMTiming::NPHASES] = timing.points;
  mine[KIFMMTiming::NPHASES + 1] = timing.bytes;
  MPI_Allreduce(mine, lo, n, MPI_DOUBLE, MPI_MIN, world);
  MPI_Allreduce(mine, hi, n, MPI_DOUBLE, MPI_MAX, world);
  MPI_Allreduce(mine, sum, n, MPI_DOUBLE, MPI_SUM, world);
  if (lmp->comm->me != 0 || timing.evaluations == 0) return;
  static const char *names[] = {"Tree", "Lists", "Upward", "M2L", "W/X", "Downward",
                                "P2P", "Comm", "Polarize", "Other"};
  double total = 0;
  for (int k = 0; k < KIFMMTiming::NPHASES; ++k) total += sum[k] / nprocs;
  std::string mesg = fmt::format(
      "\nKIFMM time breakdown ({} evaluations):\n"
      "Section  |  min time  |  avg time  |  max time  | %total\n"
      "------------------------------------------------------\n",
      timing.evaluations);
  for (int k = 0; k < KIFMMTiming::NPHASES; ++k)
    mesg += fmt::format("{:<8} | {:<10.4g} | {:<10.4g} | {:<10.4g} | {:6.2f}\n", names[k], lo[k],
                        sum[k] / nprocs, hi[k], total > 0 ? 100.0 * sum[k] / nprocs / total : 0.0);
  // communication volume: bytes this rank sent per evaluation (ghost atoms, reductions)
  const int b = KIFMMTiming::NPHASES + 1;
  const double ev = (double) timing.evaluations;
  mesg += fmt::format("{:<8} | {:<10.4g} | {:<10.4g} | {:<10.4g} | bytes sent per rank and evaluation\n",
                      "Comm B", lo[b] / ev, sum[b] / nprocs / ev, hi[b] / ev);
  const double avg_points = sum[KIFMMTiming::NPHASES] / nprocs;
  mesg += fmt::format(
      "Load: atoms of nonzero strength per rank and evaluation min/avg/max = {:.4g} / {:.4g} / "
      "{:.4g} (imbalance max/avg = {:.3g})\n",
      lo[KIFMMTiming::NPHASES] / timing.evaluations, avg_points / timing.evaluations,
      hi[KIFMMTiming::NPHASES] / timing.evaluations,
      avg_points > 0 ? hi[KIFMMTiming::NPHASES] / avg_points : 1.0);
  utils::logmesg(lmp, mesg);
}
