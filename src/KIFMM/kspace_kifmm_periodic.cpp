// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic boundaries of kspace_style kifmm (boundary p p p, cubic box): checks at init, the
// periodic cell handed to the engine at every evaluation (boxes that change size), the
// virial. The lattice sums themselves are in the engine (engine/periodic.h).
#include "kspace_kifmm.h"

#include "comm.h"
#include "domain.h"
#include "error.h"
#include "update.h"

#include <cmath>
#include <mpi.h>

using namespace LAMMPS_NS;
using kifmm_lammps::LongRangeKernel;

namespace {
const char *boundary_name(int code)
{
  switch (code) {
    case 0:
      return "p";
    case 1:
      return "f";
    case 2:
      return "s";
    default:
      return "m";
  }
}
}    // namespace

void KSpaceKIFMM::periodic_init()
{
  // 'kspace_modify pressure/scalar yes/no' (KSpace's keyword, made for msm): the constructor
  // leaves -1; a value other than the one written here last is the user's
  if (scalar_pressure_flag != scalar_pressure_written) scalar_pressure_user = scalar_pressure_flag;
  periodic = domain->xperiodic || domain->yperiodic || domain->zperiodic;
  if (!periodic) {    // open boundaries: the full virial tensor is computed
    scalar_pressure_flag = scalar_pressure_written = 0;
    return;
  }
  if (!(domain->xperiodic && domain->yperiodic && domain->zperiodic))
    error->all(FLERR,
               "kspace_style kifmm: periodic boundaries are not supported yet for mixed "
               "periodicity (boundary {} {} {}); use p p p, or f, s or m in every dimension",
               boundary_name(domain->boundary[0][0]), boundary_name(domain->boundary[1][0]),
               boundary_name(domain->boundary[2][0]));
  if (kset.kernel == LongRangeKernel::Gravity && !kset.jeans)
    error->all(FLERR,
               "kspace_style kifmm: kernel gravity with periodic boundaries diverges (the mean "
               "density is not zero); use 'kspace_modify kifmm jeans yes' to subtract it "
               "(uniform negative background, Jeans swindle)");
  periodic_cell();
  // only the trace of the periodic virial is computed (periodic_virial): LAMMPS's flag for
  // scalar-only kspace pressures makes compute pressure refuse tensor components (thermo pxx,
  // fix npt/nph aniso or tri, fix box/relax aniso, ...) instead of using wrong ones
  if (scalar_pressure_user == 0)
    error->all(FLERR,
               "kspace_style kifmm: 'kspace_modify pressure/scalar no' is not available with "
               "periodic boundaries: only the trace of the periodic virial (the scalar pressure) "
               "is computed, not its tensor components");
  scalar_pressure_flag = scalar_pressure_written = 1;
  // net charge: like ewald/pppm, a uniform neutralizing background (energy included)
  if (kset.kernel == LongRangeKernel::Coulomb && std::fabs(qsum) > 1.0e-5 && comm->me == 0)
    error->warning(FLERR,
                   "kspace_style kifmm: periodic system with net charge {:.8g}: a uniform "
                   "neutralizing background is included (energy -pi Q^2/(2 V alpha^2) as in "
                   "kspace_style ewald/pppm)",
                   qsum);
}

// The box is the periodic cell: cubic (within 1e-10 relative), handed to the engine at every
// evaluation so that fix deform, fix npt and change_box are followed.
void KSpaceKIFMM::periodic_cell()
{
  const double lx = domain->xprd, ly = domain->yprd, lz = domain->zprd;
  const double tol = 1e-10 * std::max(lx, std::max(ly, lz));
  if (std::fabs(lx - ly) > tol || std::fabs(lx - lz) > tol)
    error->all(FLERR,
               "kspace_style kifmm: periodic boundaries need a cubic box; the box lengths are "
               "{:.10g} {:.10g} {:.10g} (step {})",
               lx, ly, lz, update->ntimestep);
  if (!engine) return;
  const double center[3] = {0.5 * (domain->boxlo[0] + domain->boxhi[0]),
                            0.5 * (domain->boxlo[1] + domain->boxhi[1]),
                            0.5 * (domain->boxlo[2] + domain->boxhi[2])};
  // yukawa on a grid chosen by the cost model (grid auto): its grid kernels depend on kappa
  // times the box length and would be computed again (0.1-0.5 s) at every change of the box
  // size: the first change switches to the octree (same order and leaf size)
  const kifmm::Options &o = engine->options();
  if (kset.kernel == LongRangeKernel::Yukawa && kset.grid < 0 && o.periodic_grid > 0 && o.fixed_root &&
      o.root_half_width != 0.5 * lx) {
    kifmm::Options octree = o;
    octree.periodic_grid = 0;
    engine = kifmm::make_evaluator(engine->kernel(), octree);
    engine_options = engine->options();
    reported_first_evaluation = false;
    if (comm->me == 0)
      utils::logmesg(lmp,
                     "  KIFMM: the box changes size (step {}): kernel yukawa switches from the "
                     "single-level grid to the octree (leaf size {}), whose tables do not depend on "
                     "the box length\n",
                     update->ntimestep, engine_options.leaf_size);
  }
  engine->set_root(center, 0.5 * lx);
}

// Global virial of the periodic system. Coulomb and gravity are homogeneous of degree -1 in all
// lengths (positions and cell; the tin-foil sum and the background term included), so the trace
// of the virial equals the energy: W_xx = W_yy = W_zz = U/3 gives the exact scalar pressure.
// The anisotropic part is not computed: scalar_pressure_flag = 1 (periodic_init) makes LAMMPS's
// compute pressure stop when tensor components are asked for. Yukawa: not computed (0, warning).
void KSpaceKIFMM::periodic_virial(double e_local)
{
  for (int k = 0; k < 6; ++k) virial[k] = 0.0;
  if (kset.kernel == LongRangeKernel::Yukawa) {
    if (!warned_periodic_virial && comm->me == 0)
      error->warning(FLERR,
                     "kspace_style kifmm: the virial of periodic yukawa is not computed (0); "
                     "the pressure has no long-range part");
    warned_periodic_virial = true;
    return;
  }
  double u = 0.0;
  MPI_Allreduce(&e_local, &u, 1, MPI_DOUBLE, MPI_SUM, world);
  virial[0] = virial[1] = virial[2] = u / 3.0;
}
