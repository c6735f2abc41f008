// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Polarizable atoms of kspace_style kifmm: the interface of a fix that gives atoms induced
// point dipoles (fix kifmm/polarize). The kspace style finds the fix implementing it among the
// fixes at its init; at every evaluation it solves for the induced dipoles with its own field
// evaluations (kifmm::solve_induced_dipoles), writes them to atom->mu and then sums the forces,
// torques and energy of all charges and dipoles. The fix knows nothing of the kspace style
// beyond this interface.
#pragma once

#include "kifmm.h"
#include "pointers.h"

#include <type_traits>

namespace LAMMPS_NS {

class KIFMMPolarization {
 public:
  // as LAMMPS's Pointers (noexcept(false) where LAMMPS errors may throw from destructors): the
  // fix implementing this interface is also a Fix
  virtual ~KIFMMPolarization() noexcept(std::is_nothrow_destructible_v<Pointers>) {}

  // ID of the fix (for messages)
  virtual const char *polarization_id() const = 0;
  // local atom i carries an induced dipole (it is in the fix's group)
  virtual bool polarizable(int i) const = 0;
  // Collective, before each solve: the polarizabilities and external fields of this step
  virtual void prepare() = 0;
  // after prepare(): the polarizability volume of local atom i (distance^3: mu = alpha E /
  // qqrd2e, E in force/charge units) and the external field at it (force/charge, qe2f times
  // the field of the fix efield instances whose groups hold it)
  virtual double polarizability(int i) const = 0;
  virtual void external_field(int i, double e[3]) const = 0;
  // The start of the solve at local atom i from the dipole it carries (the last solve's, mu):
  // extrapolated from the solve before when the fix predicts; and that dipole kept for the next
  // prediction
  virtual void start_guess(int i, const double mu[3], double start[3]) = 0;
  // the solve: relative residual wanted, most iterations
  virtual double tolerance() const = 0;
  virtual int max_iterations() const = 0;
  // Collective: the outcome of this step's solve (reported by the fix; not converged: a warning)
  virtual void solved(const kifmm::PolarizationSolve &result) = 0;
};

}    // namespace LAMMPS_NS
