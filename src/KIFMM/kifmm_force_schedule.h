// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// When kspace_style kifmm evaluates its sum and what it does with the forces: the interface of a
// fix that schedules the long-range evaluations (fix kifmm/stride: multiple time stepping). The
// kspace style finds the fix implementing it among the fixes at its init and asks it at every
// compute() call; the fix knows nothing of the kspace style beyond this interface.
#pragma once

#include "pointers.h"

#include <functional>
#include <type_traits>

namespace LAMMPS_NS {

class KIFMMForceSchedule {
 public:
  // what one compute() call of the kspace style does
  enum class Action {
    Plain,         // evaluate and apply as without a schedule (minimization)
    Evaluate,      // evaluate, apply force_scale() x the forces, store() them
    EnergyOnly,    // held forces applied by plan(); evaluate energy/virial, apply no forces
    Skip           // held forces (or none) applied by plan(); last energy/virial reported
  };
  // as LAMMPS's Pointers (noexcept(false) where LAMMPS errors may throw from destructors): the
  // fix implementing this interface is also a Fix
  virtual ~KIFMMForceSchedule() noexcept(std::is_nothrow_destructible_v<Pointers>) {}

  // This call's action. For Skip and EnergyOnly in hold mode the held forces have been added
  // to atom->f; for Skip, energy and (when want_virial) virial are set to the last evaluated
  // values. in_sum(i): local atom i takes part in the long-range sum (nonzero strength).
  virtual Action plan(bool want_global, bool want_peratom, bool want_virial, double &energy,
                      double *virial, const std::function<bool(int)> &in_sum) = 0;
  // factor on the forces of this action (impulse mode: N on evaluation steps)
  virtual double force_scale(Action a) const = 0;
  // energy and virial are wanted on every evaluation (reported on the skipped steps)
  virtual bool keeps_energy() const = 0;
  // an Evaluate call: begin, the long-range force f and torque t (null: none, no dipoles) of
  // every local atom i at position x (before force_scale()), end with the evaluated energy and
  // virial
  virtual void begin_evaluation() = 0;
  virtual void store(int i, const double *f, const double *t, const double *x) = 0;
  virtual void end_evaluation(double energy, const double *virial) = 0;
};

}    // namespace LAMMPS_NS
