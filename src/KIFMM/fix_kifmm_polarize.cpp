// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "fix_kifmm_polarize.h"

#include "lammps_api.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "input.h"
#include "memory.h"
#include "modify.h"
#include "update.h"
#include "utils.h"
#include "variable.h"

#include <cmath>
#include <cstring>
#include <mpi.h>

using namespace LAMMPS_NS;

FixKIFMMPolarize::FixKIFMMPolarize(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  bool have_alpha = false;
  for (int iarg = 3; iarg < narg; iarg += 2) {
    if (iarg + 1 >= narg) error->all(FLERR, "fix kifmm/polarize: keyword {} needs a value", arg[iarg]);
    const std::string key = arg[iarg], val = arg[iarg + 1];
    if (key == "alpha" || key == "permittivity") {
      if (have_alpha)
        error->all(FLERR, "fix kifmm/polarize: give the polarizability once (alpha or permittivity)");
      have_alpha = true;
      if (key == "permittivity") {
        source = Source::Permittivity;
        permittivity = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
        if (!(permittivity > 0))
          error->all(FLERR, "fix kifmm/polarize: permittivity {} must be positive", val);
      } else if (utils::strmatch(val, "^v_")) {
        source = Source::Variable;
        alpha_variable = val.substr(2);
      } else {
        source = Source::Constant;
        alpha_constant = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
        if (!(alpha_constant >= 0))
          error->all(FLERR, "fix kifmm/polarize: alpha {} must be zero or positive", val);
      }
    } else if (key == "tol") {
      tol = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      if (!(tol > 0 && tol < 1)) error->all(FLERR, "fix kifmm/polarize: tol {} must be in (0, 1)", val);
    } else if (key == "predict") {
      if (val != "yes" && val != "no")
        error->all(FLERR, "fix kifmm/polarize: predict must be yes or no, not '{}'", val);
      predict = val == "yes";
    } else if (key == "maxiter") {
      maxiter = utils::inumeric(FLERR, arg[iarg + 1], false, lmp);
      if (maxiter < 1) error->all(FLERR, "fix kifmm/polarize: maxiter {} must be positive", val);
    } else {
      error->all(FLERR, "fix kifmm/polarize: unknown keyword '{}'", key);
    }
  }
  if (!have_alpha)
    error->all(FLERR, "fix kifmm/polarize: the polarizability is missing (alpha VALUE, alpha v_name or "
                      "permittivity EPS)");
  scalar_flag = 1;    // the polarization energy
  extscalar = 1;
  energy_global_flag = 1;
  vector_flag = 1;    // iterations, residual and field evaluations of the last solve
  size_vector = 3;
  extvector = 0;
  global_freq = 1;
  create_attribute = 1;
  maxexchange = NCOL;
  grow_arrays(atom->nmax);
  atom->add_callback(Atom::GROW);
  for (int i = 0; i < atom->nlocal; ++i) set_arrays(i);
}

FixKIFMMPolarize::~FixKIFMMPolarize()
{
  if (atom) atom->delete_callback(id, Atom::GROW);
  memory->destroy(history);
}

int FixKIFMMPolarize::setmask()
{
  return 0;    // no time-integration hooks: kspace kifmm solves at its evaluations
}

void FixKIFMMPolarize::init()
{
  if (!force->kspace || !force->kspace_match("^kifmm", 0))
    error->all(FLERR, "fix kifmm/polarize requires kspace_style kifmm (it solves for the induced dipoles)");
  if (!atom->mu_flag || !atom->torque_flag)
    error->all(FLERR, "fix kifmm/polarize: the atoms need dipole moments and torques (atom_style hybrid "
                      "sphere dipole, or dipole with a torque attribute)");
  if (source == Source::Permittivity && !atom->radius_flag)
    error->all(FLERR, "fix kifmm/polarize: permittivity needs atom radii (atom_style hybrid sphere dipole)");
  if (source == Source::Variable) {
    const int ivar = input->variable->find(alpha_variable.c_str());
    if (ivar < 0) error->all(FLERR, "fix kifmm/polarize: variable {} does not exist", alpha_variable);
    if (!input->variable->atomstyle(ivar))
      error->all(FLERR, "fix kifmm/polarize: variable {} is not atom-style", alpha_variable);
  }
  if (utils::strmatch(update->integrate_style, "^respa"))
    error->all(FLERR, "fix kifmm/polarize cannot be used with run_style respa");
  // the external field: every fix efield (constant, everywhere); other field fixes are not read
  fields.clear();
  for (int k = 0; k < modify->nfix; ++k) {
    Fix *f = modify->fix[k];
    if (!utils::strmatch(f->style, "^efield")) continue;
    ExternalField ef{f->groupbit, {0, 0, 0}};
    const std::string why = kifmm_lammps::efield_constant_field(lmp, f, ef.e);
    if (!why.empty())
      error->all(FLERR, "fix kifmm/polarize: the field of fix {} (style {}) cannot be its external field: {}; "
                        "it takes a constant, uniform fix efield",
                 f->id, f->style, why);
    fields.push_back(ef);
  }
  warned_step = -1;
}

void FixKIFMMPolarize::prepare()
{
  // the prediction: linear in time through the solutions of the last two solve steps (none at
  // the step of the last solve, e.g. a run 0 again, or with fewer than two solves before)
  const bigint step = update->ntimestep;
  new_step = step != last_step;
  extrapolation = predict && new_step && last_step > previous_step && previous_step >= 0 && step > last_step
      ? (double) (step - last_step) / (double) (last_step - previous_step)
      : 0.0;
  if (new_step) {
    previous_step = last_step;
    last_step = step;
  }
  evaluate_alpha();
}

// alpha v_name: the variable's values on the local atoms (collective)
void FixKIFMMPolarize::evaluate_alpha()
{
  if (source != Source::Variable) return;
  alpha_atom.assign(atom->nmax, 0.0);
  const int ivar = input->variable->find(alpha_variable.c_str());
  if (ivar < 0) error->all(FLERR, "fix kifmm/polarize: variable {} does not exist", alpha_variable);
  input->variable->compute_atom(ivar, igroup, alpha_atom.data(), 1, 0);
  for (int i = 0; i < atom->nlocal; ++i)
    if ((atom->mask[i] & groupbit) && !(alpha_atom[i] >= 0 && std::isfinite(alpha_atom[i])))
      error->one(FLERR, "fix kifmm/polarize: variable {} gives atom {} the polarizability {} (it must be zero "
                        "or positive)",
                 alpha_variable, atom->tag[i], alpha_atom[i]);
}

double FixKIFMMPolarize::alpha_of(int i) const
{
  if (!(atom->mask[i] & groupbit)) return 0.0;
  switch (source) {
    case Source::Constant:
      return alpha_constant;
    case Source::Variable:
      return (std::size_t) i < alpha_atom.size() ? alpha_atom[i] : 0.0;
    case Source::Permittivity: {
      // Clausius-Mossotti: a sphere of permittivity eps in a medium of eps_m (dielectric command)
      const double r = atom->radius[i], em = force->dielectric;
      return r * r * r * (permittivity - em) / (permittivity + 2.0 * em);
    }
  }
  return 0.0;
}

bool FixKIFMMPolarize::polarizable(int i) const
{
  return atom->mask[i] & groupbit;
}

double FixKIFMMPolarize::polarizability(int i) const
{
  return alpha_of(i);
}

void FixKIFMMPolarize::external_field(int i, double e[3]) const
{
  e[0] = e[1] = e[2] = 0.0;
  for (const ExternalField &f : fields)
    if (atom->mask[i] & f.groupbit)
      for (int d = 0; d < 3; ++d) e[d] += f.e[d];
}

// Linear extrapolation in time of the last two solutions, mu_n + f (mu_n - mu_(n-1)) with
// f = (step - step_n) / (step_n - step_(n-1)) (2 mu_n - mu_(n-1) at every step; a predictor of
// smoothly moving dipoles, which the solve then corrects to the tolerance)
void FixKIFMMPolarize::start_guess(int i, const double mu[3], double start[3])
{
  double *h = history[i];
  const double f = h[VALID] != 0.0 ? extrapolation : 0.0;
  for (int d = 0; d < 3; ++d) start[d] = mu[d] + f * (mu[d] - h[PREVIOUS + d]);
  if (!new_step) return;    // a solve again at the same step: the history stays
  for (int d = 0; d < 3; ++d) h[PREVIOUS + d] = mu[d];
  h[VALID] = 1.0;
}

void FixKIFMMPolarize::solved(const kifmm::PolarizationSolve &result)
{
  last = result;
  solved_once = true;
  if (result.indefinite)
    error->all(FLERR, "fix kifmm/polarize: the induced dipoles have no stable solution at step {} (the "
                      "polarizabilities are too large for the distances between the atoms: point dipoles "
                      "this close polarize each other without bound); use smaller alpha or keep the atoms apart",
               update->ntimestep);
  if (!std::isfinite(result.residual))
    error->all(FLERR, "fix kifmm/polarize: the solve for the induced dipoles gave non-finite values at step {}",
               update->ntimestep);
  if (!result.converged && warned_step < 0) {
    warned_step = update->ntimestep;
    if (comm->me == 0)
      error->warning(FLERR, "fix kifmm/polarize: the induced dipoles did not converge in {} iterations at step "
                            "{} (relative residual {:.3g}, tol {:.3g}); raise maxiter or tol (said once per run)",
                     result.iterations, update->ntimestep, result.residual, tol);
  }
}

// polarization energy sum_i qqrd2e mu_i^2 / (2 alpha_i) of the group's dipoles
double FixKIFMMPolarize::compute_scalar()
{
  evaluate_alpha();    // not prepare(): the energy at any step leaves the solve's steps alone
  double local = 0.0, all = 0.0;
  double **mu = atom->mu;
  for (int i = 0; i < atom->nlocal; ++i) {
    const double a = alpha_of(i);
    if (a > 0) local += (mu[i][0] * mu[i][0] + mu[i][1] * mu[i][1] + mu[i][2] * mu[i][2]) / (2.0 * a);
  }
  MPI_Allreduce(&local, &all, 1, MPI_DOUBLE, MPI_SUM, world);
  return force->qqrd2e * all;
}

double FixKIFMMPolarize::compute_vector(int n)
{
  if (n == 0) return last.iterations;
  if (n == 1) return last.residual;
  return last.evaluations;
}

double FixKIFMMPolarize::memory_usage()
{
  return (double) alpha_atom.capacity() * sizeof(double) + (double) atom->nmax * NCOL * sizeof(double);
}

void FixKIFMMPolarize::grow_arrays(int nmax)
{
  memory->grow(history, nmax, NCOL, "kifmm/polarize:history");
}

void FixKIFMMPolarize::copy_arrays(int i, int j, int)
{
  for (int k = 0; k < NCOL; ++k) history[j][k] = history[i][k];
}

void FixKIFMMPolarize::set_arrays(int i)
{
  for (int k = 0; k < NCOL; ++k) history[i][k] = 0.0;    // no solve before: start from mu
}

int FixKIFMMPolarize::pack_exchange(int i, double *buf)
{
  for (int k = 0; k < NCOL; ++k) buf[k] = history[i][k];
  return NCOL;
}

int FixKIFMMPolarize::unpack_exchange(int nlocal, double *buf)
{
  for (int k = 0; k < NCOL; ++k) history[nlocal][k] = buf[k];
  return NCOL;
}
