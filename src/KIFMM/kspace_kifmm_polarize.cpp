// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Induced point dipoles in kspace_style kifmm (fix kifmm/polarize, through KIFMMPolarization):
// before the forces of a step are evaluated, the dipoles of the polarizable atoms are solved
// for with the engine's field evaluations,
//   mu_i / alpha_i - e_i(mu) = e0_i,   e0_i = E_ext,i / qqrd2e - grad phi_fixed(x_i)
// (kernel units: phi of the charges and of the permanent dipoles of the other atoms; e(mu) the
// field -grad phi of the induced dipoles), by kifmm::solve_induced_dipoles started from the
// dipoles the atoms carry (the last step's), extrapolated from the step before by the fix. The
// result goes into atom->mu and the moments of the evaluation that follows, which gives the
// forces q E + (mu . grad) E, torques and energy of the converged dipoles. Several ranks: every
// field evaluation is distributed (each rank passes its own points).
#include "kspace_kifmm.h"

#include "kifmm_polarization.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "modify.h"

#include <cmath>
#include <mpi.h>

using namespace LAMMPS_NS;
using kifmm_lammps::LongRangeKernel;

void KSpaceKIFMM::find_polarization()
{
  polarization = nullptr;
  for (int k = 0; k < modify->nfix; ++k)
    if (auto *p = dynamic_cast<KIFMMPolarization *>(modify->fix[k])) {
      if (polarization)
        error->all(FLERR, "kspace_style kifmm: only one fix kifmm/polarize is allowed (fixes {} and {})",
                   polarization->polarization_id(), p->polarization_id());
      polarization = p;
    }
  if (polarization && kset.kernel == LongRangeKernel::Gravity)
    error->all(FLERR, "fix kifmm/polarize needs kspace_style kifmm with kernel coulomb or yukawa, not gravity");
}

void KSpaceKIFMM::polarize_points()
{
  polarization->prepare();
  const std::size_t n = index.size();
  std::vector<std::size_t> pol;    // the polarizable points, their alpha, positions, start guess
  std::vector<double> alpha, pxyz, mu, e0;
  for (std::size_t k = 0; k < n; ++k) {
    const int i = index[k];
    if (!polarization->polarizable(i)) continue;
    pol.push_back(k);
    alpha.push_back(polarization->polarizability(i));
    double ext[3], start[3];
    polarization->external_field(i, ext);
    polarization->start_guess(i, &moment[3 * k], start);
    for (int d = 0; d < 3; ++d) {
      pxyz.push_back(xyz[3 * k + d]);
      mu.push_back(start[d]);
      e0.push_back(ext[d] / qqrd2e);
      moment[3 * k + d] = 0.0;    // the fixed sources: no induced dipoles
    }
  }
  const std::size_t m = pol.size();
  std::vector<double> g(3 * m);
  auto sum = [this](double x) {
    double y = 0;
    MPI_Allreduce(&x, &y, 1, MPI_DOUBLE, MPI_SUM, world);
    return y;
  };

  // the field of the charges and permanent dipoles at the polarizable points
  int mine = 0, any = 0;
  for (std::size_t k = 0; k < n && !mine; ++k)
    mine = strength[k] != 0.0 || moment[3 * k] != 0.0 || moment[3 * k + 1] != 0.0 || moment[3 * k + 2] != 0.0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, world);
  if (any) {
    if (distributed()) {    // at all own points, kept at the polarizable ones
      std::vector<double> gall(3 * n);
      engine->evaluate_dipoles_distributed(*kcomm, n, xyz.data(), strength.data(), moment.data(), nullptr,
                                           gall.data(), nullptr);
      for (std::size_t s = 0; s < m; ++s)
        for (int d = 0; d < 3; ++d) g[3 * s + d] = gall[3 * pol[s] + d];
    } else if (m > 0) {
      engine->evaluate_dipoles(n, xyz.data(), strength.data(), moment.data(), m, pxyz.data(), nullptr, g.data(),
                               nullptr);
    }
    for (std::size_t q = 0; q < 3 * m; ++q) e0[q] -= g[q];
  }

  // the field of the induced dipoles (sources = targets: the mutual near field)
  auto field = [&](const double *dip, double *e) {
    if (distributed()) {
      engine->evaluate_dipoles_distributed(*kcomm, m, pxyz.data(), nullptr, dip, nullptr, g.data(), nullptr);
    } else if (m > 0) {
      engine->evaluate_dipoles(m, pxyz.data(), nullptr, dip, m, pxyz.data(), nullptr, g.data(), nullptr);
    }
    for (std::size_t q = 0; q < 3 * m; ++q) e[q] = -g[q];
  };
  const kifmm::PolarizationSolve r = kifmm::solve_induced_dipoles(
      m, alpha.data(), e0.data(), field, sum, polarization->tolerance(), polarization->max_iterations(), mu.data());
  polarization->solved(r);

  for (std::size_t s = 0; s < m; ++s) {
    const std::size_t k = pol[s];
    double *amu = atom->mu[index[k]];
    for (int d = 0; d < 3; ++d) moment[3 * k + d] = amu[d] = mu[3 * s + d];
    amu[3] = std::sqrt(amu[0] * amu[0] + amu[1] * amu[1] + amu[2] * amu[2]);
  }
}
