// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix ID group kifmm/polarize alpha A|v_name | permittivity EPS  [tol T] [maxiter N] [predict yes|no]
//
// Induced point dipoles on the atoms of the group: mu_i = alpha_i (E_ext + E_i) / qqrd2e,
// E_i the field of all other charges and dipoles, E_ext that of the fix efield instances,
// solved by kspace_style kifmm at every evaluation (KIFMMPolarization). The fix holds the
// settings, the polarizabilities and external fields of a step, reports the solve, and adds
// the polarization energy sum_i qqrd2e mu_i^2 / (2 alpha_i) (fix_modify energy yes).
// See doc/fix_kifmm_polarize.rst.
#pragma once

#include "fix.h"
#include "kifmm_polarization.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {

class FixKIFMMPolarize : public Fix, public KIFMMPolarization {
 public:
  FixKIFMMPolarize(class LAMMPS *, int, char **);
  ~FixKIFMMPolarize() override;
  int setmask() override;
  void init() override;
  double compute_scalar() override;
  double compute_vector(int) override;
  double memory_usage() override;
  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;

  // ---- KIFMMPolarization: called by the kspace style's compute()
  const char *polarization_id() const override { return id; }
  bool polarizable(int i) const override;
  void prepare() override;
  double polarizability(int i) const override;
  void external_field(int i, double e[3]) const override;
  void start_guess(int i, const double mu[3], double start[3]) override;
  double tolerance() const override { return tol; }
  int max_iterations() const override { return maxiter; }
  void solved(const kifmm::PolarizationSolve &result) override;

 private:
  enum class Source { Constant, Variable, Permittivity };
  Source source = Source::Constant;
  double alpha_constant = 0.0;
  std::string alpha_variable;    // atom-style variable name (without v_)
  double permittivity = 0.0;     // of the spheres; the medium's is the dielectric command's
  double tol = 1.0e-6;
  int maxiter = 100;
  bool predict = true;
  // per atom: the dipole of the solve before the last one (3) and whether it is set; moves with
  // the atom (exchange), not kept in restart files
  enum { PREVIOUS = 0, VALID = 3, NCOL = 4 };
  double **history = nullptr;
  // steps of the last two solves; this solve's extrapolation factor and whether it is at a new
  // step (then the dipoles the atoms carry become the history)
  bigint last_step = -1, previous_step = -1;
  double extrapolation = 0.0;
  bool new_step = true;
  std::vector<double> alpha_atom;    // this step's polarizabilities of the local atoms (variable)
  struct ExternalField {
    int groupbit;
    double e[3];
  };
  std::vector<ExternalField> fields;
  kifmm::PolarizationSolve last;
  bool solved_once = false;
  bigint warned_step = -1;
  double alpha_of(int i) const;
  void evaluate_alpha();
};

}    // namespace LAMMPS_NS
