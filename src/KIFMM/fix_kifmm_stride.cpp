// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "fix_kifmm_stride.h"


#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "modify.h"
#include "pair.h"
#include "update.h"
#include "utils.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mpi.h>

using namespace LAMMPS_NS;

namespace {
constexpr int restart_version = 1;
constexpr int restart_size = 18;
}    // namespace

FixKIFMMStride::FixKIFMMStride(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  if (narg < 4)
    error->all(FLERR, "Illegal fix kifmm/stride command: expected N or auto after the style");
  if (igroup != 0)
    error->all(FLERR, "fix kifmm/stride must use group all (the kspace acts on all atoms)");
  if (strcmp(arg[3], "auto") == 0) {
    auto_mode = true;
    nevery = 1;    // every step until the stiffness probe has chosen N
  } else {
    nevery = utils::inumeric(FLERR, arg[3], false, lmp);
    if (nevery < 1) error->all(FLERR, "fix kifmm/stride: N = {} must be a positive integer", arg[3]);
  }
  for (int iarg = 4; iarg < narg; iarg += 2) {
    if (iarg + 1 >= narg)
      error->all(FLERR, "fix kifmm/stride: keyword {} needs a value", arg[iarg]);
    const std::string key = arg[iarg], val = arg[iarg + 1];
    if (key == "mode") {
      if (val == "hold")
        mode = Mode::Hold;
      else if (val == "impulse")
        mode = Mode::Impulse;
      else
        error->all(FLERR, "fix kifmm/stride: mode must be hold or impulse, not '{}'", val);
    } else if (key == "energy") {
      if (val == "last")
        energy_every = false;
      else if (val == "every")
        energy_every = true;
      else
        error->all(FLERR, "fix kifmm/stride: energy must be last or every, not '{}'", val);
    } else if (key == "kdem") {
      kdem = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      if (!(kdem > 0.0)) error->all(FLERR, "fix kifmm/stride: kdem {} must be positive", val);
      kdem_source = "kdem keyword";
    } else if (key == "nmax") {
      nmax_auto = utils::inumeric(FLERR, arg[iarg + 1], false, lmp);
      if (nmax_auto < 1) error->all(FLERR, "fix kifmm/stride: nmax {} must be positive", val);
    } else {
      error->all(FLERR, "fix kifmm/stride: unknown keyword '{}'", key);
    }
  }

  restart_global = 1;
  restart_peratom = 1;
  create_attribute = 1;
  maxexchange = NCOL;
  vector_flag = 1;
  size_vector = 8;
  global_freq = 1;
  extvector = 0;
  peratom_flag = 1;
  size_peratom_cols = 3;    // f_ID[1..3]: the cached long-range force
  peratom_freq = 1;

  grow_arrays(atom->nmax);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
  for (int i = 0; i < atom->nlocal; ++i) set_arrays(i);
}

FixKIFMMStride::~FixKIFMMStride()
{
  if (atom) {
    atom->delete_callback(id, Atom::GROW);
    atom->delete_callback(id, Atom::RESTART);
  }
  memory->destroy(cache);
}

int FixKIFMMStride::setmask()
{
  return 0;    // no time-integration hooks: the kspace calls plan() from its compute()
}

void FixKIFMMStride::init()
{
  if (!force->kspace_match("^kifmm", 0))
    error->all(FLERR, "fix kifmm/stride requires kspace_style kifmm");
  if (utils::strmatch(update->integrate_style, "^respa"))
    error->all(FLERR,
               "fix kifmm/stride cannot be used with run_style respa (r-RESPA already "
               "evaluates the kspace on its outer level only)");
  int count = 0;
  for (int i = 0; i < modify->nfix; ++i)
    if (strcmp(modify->fix[i]->style, style) == 0) ++count;
  if (count > 1) error->all(FLERR, "Only one fix kifmm/stride may be defined");

  // contact stiffness: keyword, else whatever the pair style exports as "kn"
  if (kdem_source != "kdem keyword") {
    kdem = 0.0;
    kdem_source.clear();
    if (force->pair) {
      int dim = -1;
      auto *kn = static_cast<double *>(force->pair->extract("kn", dim));
      if (kn && dim == 0 && *kn > 0.0) {
        kdem = *kn;
        kdem_source = fmt::format("pair {} kn", force->pair_style);
      }
    }
  }
  if (auto_mode && !(kdem > 0.0))
    error->all(FLERR,
               "fix kifmm/stride auto needs the contact stiffness: add kdem K (pair style {} "
               "does not export its normal stiffness kn)",
               force->pair_style ? force->pair_style : "none");
}

void FixKIFMMStride::setup(int)
{
  advised_this_run = false;
  if (comm->me != 0) return;
  std::string mesg = fmt::format(
      "fix kifmm/stride: long-range forces evaluated on steps that are multiples of N = {}{}, "
      "mode {}; ",
      nevery, auto_mode ? (auto_chosen ? " (chosen by auto)" : " (auto: probing)") : "",
      mode == Mode::Hold ? "hold" : "impulse");
  if (energy_every)
    mesg += "energy every: elong and the kspace virial are evaluated whenever output needs them\n";
  else
    mesg += fmt::format("energy last: on other steps elong and the kspace virial are those of the "
                        "last evaluation (its step is f_{}[2])\n",
                        id);
  if (k_lr >= 0.0) {
    const double s = recommended_stride();
    mesg += fmt::format("  last measured k_LR = {:.4g}", k_lr);
    if (s > 0.0) mesg += fmt::format(", S = sqrt(k_DEM/k_LR) = {:.3g}", s);
    mesg += "\n";
  } else {
    mesg += fmt::format("  k_LR will be measured between evaluations {} steps or more apart; ",
                        probe_gap());
    mesg += kdem > 0.0 ? fmt::format("k_DEM = {:.4g} ({})\n", kdem, kdem_source)
                       : std::string("k_DEM unknown (give kdem K for a recommended N)\n");
  }
  utils::logmesg(lmp, mesg);
  // no step of this run after its first is a multiple of N: no evaluation during the run
  if (!auto_mode && update->whichflag == 1 && update->nsteps > 0 && update->firststep >= 0 &&
      update->laststep / nevery == update->firststep / nevery) {
    std::string what;
    if (mode == Mode::Impulse)
      what = update->firststep % nevery == 0
          ? fmt::format("mode impulse: the kick of step {} only", update->firststep)
          : std::string("mode impulse: no long-range force");
    else
      what = last_eval_step >= 0 ? fmt::format("the forces of step {} are held throughout", last_eval_step)
                                 : std::string("no long-range forces are held");
    error->warning(FLERR,
                   "fix kifmm/stride: N = {} is longer than this run of {} steps (steps {} to {}): "
                   "the long-range forces are not evaluated again during the run ({})",
                   nevery, update->nsteps, update->firststep, update->laststep, what);
  }
}

// ---------------------------------------------------------------- schedule

FixKIFMMStride::Action FixKIFMMStride::plan(bool want_global, bool want_peratom,
                                             bool want_virial, double &energy, double *virial,
                                             const std::function<bool(int)> &in_sum)
{
  // minimization (and anything but dynamics): every call evaluates as without this fix
  if (update->whichflag != 1) return current = Action::Plain;

  const bigint step = update->ntimestep;
  if (pending_nevery > 0 && step % pending_nevery == 0) {
    nevery = pending_nevery;    // auto: switch where the new schedule starts
    pending_nevery = 0;
  }
  bool due = step % nevery == 0;
  if (!due && mode == Mode::Hold) {
    // atoms of nonzero strength without a cached force (first setup, inserted atoms, a fix
    // defined mid-simulation): evaluate now, off the schedule
    int mine = 0, any = 0;
    for (int i = 0; i < atom->nlocal && !mine; ++i)
      if (cache[i][VALID] == 0.0 && in_sum(i)) mine = 1;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, world);
    if (any) {
      due = true;
      ++n_forced;
    }
  }
  if (due) {
    new_reference = ref_step < 0 || step < ref_step || step - ref_step >= probe_gap();
    measuring = ref_step >= 0 && step - ref_step >= probe_gap();
    msum[0] = msum[1] = 0.0;
    return current = Action::Evaluate;
  }

  if (mode == Mode::Hold) add_held_forces();
  if ((energy_every && want_global) || want_peratom) {
    ++n_energy_only;
    return current = Action::EnergyOnly;
  }
  energy = last_energy;
  if (want_virial)
    for (int k = 0; k < 6; ++k) virial[k] = last_virial[k];
  return current = Action::Skip;
}

void FixKIFMMStride::add_held_forces()
{
  double **f = atom->f;
  double **torque = atom->torque_flag ? atom->torque : nullptr;
  for (int i = 0; i < atom->nlocal; ++i) {
    const double *c = cache[i];
    if (c[VALID] == 0.0) continue;
    f[i][0] += c[F];
    f[i][1] += c[F + 1];
    f[i][2] += c[F + 2];
    if (torque)    // point dipoles: the held torque (zero without dipoles)
      for (int d = 0; d < 3; ++d) torque[i][d] += c[T + d];
  }
}

void FixKIFMMStride::begin_evaluation()
{
  // atoms of zero strength get no long-range force: cached zero, valid
  for (int i = 0; i < atom->nlocal; ++i) {
    for (int d = 0; d < 3; ++d) cache[i][F + d] = cache[i][T + d] = 0.0;
    cache[i][VALID] = 1.0;
  }
}

void FixKIFMMStride::end_evaluation(double energy, const double *virial)
{
  if (current != Action::Evaluate) return;
  const bigint step = update->ntimestep;
  last_eval_step = step;
  last_energy = energy;
  for (int k = 0; k < 6; ++k) last_virial[k] = virial[k];
  ++n_evaluations;
  if (measuring) {
    double tot[2] = {0, 0};
    MPI_Allreduce(msum, tot, 2, MPI_DOUBLE, MPI_SUM, world);
    if (tot[1] > 0.0) {
      k_lr = std::sqrt(tot[0] / tot[1]);
      report_measurement();
    }
  }
  if (new_reference) ref_step = step;
  measuring = new_reference = false;
}

double FixKIFMMStride::recommended_stride() const
{
  if (!(kdem > 0.0) || k_lr < 0.0) return 0.0;
  if (k_lr == 0.0) return std::numeric_limits<double>::infinity();
  return std::sqrt(kdem / k_lr);
}

void FixKIFMMStride::report_measurement()
{
  const double s = recommended_stride();
  if (auto_mode && !auto_chosen && s > 0.0) {
    auto_chosen = true;
    int n = std::isfinite(s) ? (int) std::min<double>(std::floor(s), nmax_auto) : nmax_auto;
    n = std::max(n, 1);
    pending_nevery = n;    // takes effect on the next multiple of n
    if (comm->me == 0)
      utils::logmesg(lmp,
                     "fix kifmm/stride auto: k_LR = {:.4g}, k_DEM = {:.4g}: N = {} (S = {:.3g}, "
                     "cap nmax = {}) from step {}\n",
                     k_lr, kdem, n, s, nmax_auto, (update->ntimestep / n + 1) * n);
  }
  if (advised_this_run) return;
  advised_this_run = true;
  if (comm->me != 0) return;
  std::string mesg = fmt::format(
      "fix kifmm/stride: step {}: long-range stiffness k_LR = {:.4g} (RMS force change / RMS "
      "displacement since step {})",
      update->ntimestep, k_lr, ref_step);
  if (s > 0.0)
    mesg += fmt::format("; k_DEM = {:.4g} ({}); recommended N <= S = sqrt(k_DEM/k_LR) = {:.3g}\n",
                        kdem, kdem_source, s);
  else
    mesg += "; give kdem K (contact stiffness) for a recommended N\n";
  utils::logmesg(lmp, mesg);
  if (s > 0.0 && !auto_mode && nevery > s)
    error->warning(FLERR,
                   "fix kifmm/stride: N = {} exceeds the recommended S = sqrt(k_DEM/k_LR) = {:.3g}",
                   nevery, s);
}

double FixKIFMMStride::compute_vector(int n)
{
  switch (n) {
    case 0: return nevery;
    case 1: return (double) last_eval_step;
    case 2: return (double) n_evaluations;
    case 3: return (double) n_energy_only;
    case 4: return (double) n_forced;
    case 5: return k_lr < 0.0 ? 0.0 : k_lr;
    case 6: return kdem;
    case 7: {
      const double s = recommended_stride();
      return std::isfinite(s) ? s : 0.0;
    }
    default: return 0.0;
  }
}

double FixKIFMMStride::memory_usage()
{
  return (double) atom->nmax * NCOL * sizeof(double);
}

// ---------------------------------------------------------------- per-atom cache

void FixKIFMMStride::grow_arrays(int nmax)
{
  memory->grow(cache, nmax, NCOL, "kifmm/stride:cache");
  array_atom = cache;
}

void FixKIFMMStride::copy_arrays(int i, int j, int)
{
  memcpy(cache[j], cache[i], NCOL * sizeof(double));
}

void FixKIFMMStride::set_arrays(int i)
{
  double *c = cache[i];
  for (int k = 0; k < NCOL; ++k) c[k] = 0.0;
  c[X_REF] = std::numeric_limits<double>::quiet_NaN();    // no probe reference
}

int FixKIFMMStride::pack_exchange(int i, double *buf)
{
  memcpy(buf, cache[i], NCOL * sizeof(double));
  return NCOL;
}

int FixKIFMMStride::unpack_exchange(int nlocal, double *buf)
{
  memcpy(cache[nlocal], buf, NCOL * sizeof(double));
  return NCOL;
}

int FixKIFMMStride::pack_restart(int i, double *buf)
{
  buf[0] = NCOL + 1;    // the count first: other fixes skip over it
  memcpy(buf + 1, cache[i], NCOL * sizeof(double));
  return NCOL + 1;
}

void FixKIFMMStride::unpack_restart(int nlocal, int nth)
{
  double **extra = atom->extra;
  int m = 0;
  for (int k = 0; k < nth; ++k) m += static_cast<int>(extra[nlocal][m]);
  const int size = static_cast<int>(extra[nlocal][m]);
  if (size != NCOL + 1 && size != NCOL_FORCES + 1)
    error->one(FLERR, "fix kifmm/stride: per-atom restart data of unexpected size");
  set_arrays(nlocal);    // a file without held torques: none held
  memcpy(cache[nlocal], &extra[nlocal][m + 1], (size - 1) * sizeof(double));
}

int FixKIFMMStride::size_restart(int)
{
  return NCOL + 1;
}

int FixKIFMMStride::maxsize_restart()
{
  return NCOL + 1;
}

// ---------------------------------------------------------------- global restart

void FixKIFMMStride::write_restart(FILE *fp)
{
  double list[restart_size] = {};
  list[0] = restart_version;
  list[1] = nevery;
  list[2] = mode == Mode::Hold ? 0 : 1;
  list[3] = (double) last_eval_step;
  list[4] = last_energy;
  for (int k = 0; k < 6; ++k) list[5 + k] = last_virial[k];
  list[11] = (double) n_evaluations;
  list[12] = (double) n_energy_only;
  list[13] = (double) n_forced;
  list[14] = (double) ref_step;
  list[15] = k_lr;
  list[16] = auto_chosen ? 1 : 0;
  list[17] = pending_nevery;
  if (comm->me == 0) {
    int size = restart_size * sizeof(double);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), restart_size, fp);
  }
}

void FixKIFMMStride::restart(char *buf)
{
  const auto *list = reinterpret_cast<const double *>(buf);
  if ((int) list[0] != restart_version)
    error->all(FLERR, "fix kifmm/stride: restart data of version {} (expected {})",
               (int) list[0], restart_version);
  const int stored_n = (int) list[1];
  const Mode stored_mode = list[2] == 0 ? Mode::Hold : Mode::Impulse;
  last_eval_step = (bigint) list[3];
  last_energy = list[4];
  for (int k = 0; k < 6; ++k) last_virial[k] = list[5 + k];
  n_evaluations = (bigint) list[11];
  n_energy_only = (bigint) list[12];
  n_forced = (bigint) list[13];
  ref_step = (bigint) list[14];
  k_lr = list[15];
  if (auto_mode && list[16] != 0) {
    auto_chosen = true;
    nevery = stored_n;
    pending_nevery = (int) list[17];
  }
  if (comm->me == 0 && (stored_n != nevery || stored_mode != mode))
    error->warning(FLERR,
                   "fix kifmm/stride: restart file had N = {} mode {}, now N = {} mode {}; the "
                   "cached forces of step {} are used until the next multiple of {}",
                   stored_n, stored_mode == Mode::Hold ? "hold" : "impulse", nevery,
                   mode == Mode::Hold ? "hold" : "impulse", last_eval_step, nevery);
}
