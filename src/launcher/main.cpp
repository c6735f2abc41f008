// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// lmp_kifmm: Debian's `lmp` with the lammps-kifmm styles built in and a `plugin` command.
// Takes exactly the command-line flags of `lmp` (argv goes to LAMMPS unchanged).
#include "plugin_registry.h"

#include "input.h"
#include "lammps.h"

#include <mpi.h>

using namespace LAMMPS_NS;

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  auto *lammps = new LAMMPS(argc, argv, MPI_COMM_WORLD);
  kifmm_lammps::install_launcher_styles(lammps);
  lammps->input->file();
  delete lammps;
  MPI_Barrier(MPI_COMM_WORLD);
  MPI_Finalize();
  return 0;
}
