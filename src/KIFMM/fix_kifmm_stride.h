// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix ID all kifmm/stride N|auto [mode hold|impulse] [energy last|every] [kdem K] [nmax M]
//
// Multiple time stepping for kspace_style kifmm: the long-range forces are evaluated on steps
// that are multiples of N only. mode hold: in between, each atom gets its force of the last
// evaluation again; mode impulse: N times the force on evaluation steps, nothing in between.
// The kspace does the scheduling (it alone knows its forces apart from the others) by asking
// this fix at each compute() call (KIFMMForceSchedule::plan()); the fix owns the per-atom cache, which LAMMPS moves
// with the atoms (exchange, sort, deletion) and writes to restart files, together with the
// schedule state (last evaluation step, energy, virial). See doc/fix_kifmm_stride.rst.
#pragma once

#include "fix.h"
#include "kifmm_force_schedule.h"

#include <string>

namespace LAMMPS_NS {

class FixKIFMMStride : public Fix, public KIFMMForceSchedule {
 public:
  enum class Mode { Hold, Impulse };

  FixKIFMMStride(class LAMMPS *, int, char **);
  ~FixKIFMMStride() override;
  int setmask() override;
  void init() override;
  void setup(int) override;
  double compute_vector(int) override;
  double memory_usage() override;

  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;
  int pack_restart(int, double *) override;
  void unpack_restart(int, int) override;
  int size_restart(int) override;
  int maxsize_restart() override;
  void write_restart(FILE *) override;
  void restart(char *) override;

  // ---- KIFMMForceSchedule: called by the kspace style's compute()
  Action plan(bool want_global, bool want_peratom, bool want_virial, double &energy,
              double *virial, const std::function<bool(int)> &in_sum) override;
  double force_scale(Action a) const override
  {
    return a == Action::Evaluate && mode == Mode::Impulse ? nevery : 1.0;
  }
  // energy last: the kspace computes energy and virial on every evaluation, to report them on
  // the skipped steps (energy every evaluates them when they are wanted)
  bool keeps_energy() const override { return !energy_every && (nevery > 1 || auto_mode); }
  void begin_evaluation() override;
  void store(int i, const double *f, const double *t, const double *x) override
  {
    double *c = cache[i];
    if (t)
      for (int d = 0; d < 3; ++d) c[T + d] = t[d];
    if (measuring && c[X_REF] == c[X_REF]) {    // reference valid (not NaN)
      for (int d = 0; d < 3; ++d) {
        const double df = f[d] - c[F_REF + d], dx = x[d] - c[X_REF + d];
        msum[0] += df * df;
        msum[1] += dx * dx;
      }
    }
    for (int d = 0; d < 3; ++d) c[F + d] = f[d];
    c[VALID] = 1.0;
    if (new_reference)
      for (int d = 0; d < 3; ++d) {
        c[F_REF + d] = f[d];
        c[X_REF + d] = x[d];
      }
  }
  void end_evaluation(double energy, const double *virial) override;

 private:
  // per-atom columns: held force, valid flag, reference position and force of the k_LR probe,
  // held torque (point dipoles); restart files without the torque have NCOL_FORCES columns
  enum { F = 0, VALID = 3, X_REF = 4, F_REF = 7, T = 10, NCOL = 13, NCOL_FORCES = 10 };
  double **cache = nullptr;

  Mode mode = Mode::Hold;
  bool energy_every = false;
  bool auto_mode = false;
  bool auto_chosen = false;
  int nevery = 1;
  int pending_nevery = 0;    // auto: N chosen, starts at its next multiple
  int nmax_auto = 50;
  double kdem = 0.0;          // contact stiffness (keyword, or from the pair style)
  std::string kdem_source;    // "kdem keyword", "pair <style> kn", or empty

  // schedule state (global restart)
  bigint last_eval_step = -1;
  double last_energy = 0.0, last_virial[6] = {0, 0, 0, 0, 0, 0};
  bigint n_evaluations = 0, n_energy_only = 0, n_forced = 0;
  Action current = Action::Plain;

  // k_LR probe: RMS change of the long-range force over RMS displacement between two
  // evaluations at least `probe_gap()` steps apart
  bigint ref_step = -1;
  bool measuring = false, new_reference = false;
  double msum[2] = {0, 0};
  double k_lr = -1.0;    // negative: not measured yet
  bool advised_this_run = false;
  bigint probe_gap() const { return nevery > 10 ? nevery : 10; }
  double recommended_stride() const;
  void report_measurement();
  void add_held_forces();
};

}    // namespace LAMMPS_NS
