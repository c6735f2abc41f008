// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "kspace_kifmm.h"

#include "kifmm_force_schedule.h"
#include "kifmm_rigid_bodies.h"
#include "mpi_communicator.h"

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fix.h"
#include "force.h"
#include "group.h"
#include "input.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "pair.h"
#include "update.h"
#include "utils.h"
#include "variable.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mpi.h>
#include <new>
#include <random>
#include <stdexcept>

using namespace LAMMPS_NS;
using kifmm_lammps::LongRangeKernel;

namespace {
std::string default_cache_dir()
{
  if (const char *env = std::getenv("KIFMM_CACHE_DIR")) return env;
  if (const char *xdg = std::getenv("XDG_CACHE_HOME")) return std::string(xdg) + "/lammps-kifmm";
  if (const char *home = std::getenv("HOME")) return std::string(home) + "/.cache/lammps-kifmm";
  return "";
}
// Creates the cache directory if it is missing; returns why it cannot be used (empty: usable).
std::string make_cache_dir(const std::string &dir)
{
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return ec.message();
  if (!std::filesystem::is_directory(dir, ec)) return "not a directory";
  return "";
}
// The neigh_modify exclusions that the long-range sum does not apply, as "type 1 2, group a b,
// ...": all of them but molecule/intra on the group of a fix whose rigid bodies the kspace
// leaves out (fix clump/rigid: the pairs inside one clump).
std::string unapplied_exclusions(LAMMPS *lmp)
{
  const Neighbor *nb = lmp->neighbor;
  std::string list;
  auto add = [&](const std::string &item) { list += (list.empty() ? "" : ", ") + item; };
  for (int k = 0; k < nb->nex_type; ++k) add(fmt::format("type {} {}", nb->ex1_type[k], nb->ex2_type[k]));
  for (int k = 0; k < nb->nex_group; ++k)
    add(fmt::format("group {} {}", lmp->group->names[nb->ex1_group[k]], lmp->group->names[nb->ex2_group[k]]));
  for (int k = 0; k < nb->nex_mol; ++k) {
    bool bodies = false;
    for (int i = 0; i < lmp->modify->nfix && nb->ex_mol_intra[k]; ++i)
      if (dynamic_cast<KIFMMRigidBodies *>(lmp->modify->fix[i]) &&
          lmp->modify->fix[i]->igroup == nb->ex_mol_group[k])
        bodies = true;
    if (!bodies)
      add(fmt::format("molecule/{} {}", nb->ex_mol_intra[k] ? "intra" : "inter",
                      lmp->group->names[nb->ex_mol_group[k]]));
  }
  return list;
}
const char *error_variable = "kifmm_error";    // also in kspace_kifmm_error.cpp
const char *timing_fix_id = "KIFMM_TIMING";
}    // namespace

KSpaceKIFMM::KSpaceKIFMM(LAMMPS *lmp) : KSpace(lmp)
{
  // the full long-range sum: no real-space split, no g_ewald for pair styles
  ewaldflag = pppmflag = msmflag = dispersionflag = tip4pflag = dipoleflag = spinflag = 0;
  triclinic_support = 0;
  scalar_pressure_flag = -1;    // 'kspace_modify pressure/scalar' not given (periodic_init)
}

KSpaceKIFMM::~KSpaceKIFMM()
{
  if (modify && modify->find_fix(timing_fix_id) >= 0) modify->delete_fix(timing_fix_id);
}

void KSpaceKIFMM::settings(int narg, char **arg)
{
  if (narg != 1)
    error->all(FLERR, "Illegal kspace_style kifmm command: expected 1 argument (ACCURACY), got {}",
               narg);
  std::string why = kifmm_lammps::parse_accuracy(arg[0], kset);
  if (!why.empty()) error->all(FLERR, why);
  accuracy_relative = kset.accuracy;
}

int KSpaceKIFMM::modify_param(int narg, char **arg)
{
  if (strcmp(arg[0], "kifmm") != 0) return 0;
  std::vector<std::string> args(arg, arg + narg);
  int consumed = 0;
  std::string why = kifmm_lammps::parse_kifmm_keywords(args, kset, consumed);
  if (!why.empty()) error->all(FLERR, why);
  engine.reset();    // settings changed: new evaluator at init
  chosen_order = 0;
  if (kset.check_every > 0) {
    // the measured error goes to an internal-style variable usable as v_kifmm_error
    int ivar = input->variable->find(error_variable);
    if (ivar < 0)
      input->variable->set(std::string(error_variable) + " internal -1");
    else if (!input->variable->internalstyle(ivar))
      error->all(FLERR, "kspace_modify kifmm check: variable {} exists and is not internal-style",
                 error_variable);
  }
  return consumed;
}

double KSpaceKIFMM::strength_of(int i) const
{
  if (kset.kernel == LongRangeKernel::Gravity)
    return atom->rmass ? atom->rmass[i] : atom->mass[atom->type[i]];
  return atom->q[i];
}

// Atoms of nonzero strength on all ranks (the sources and targets of an evaluation).
bigint KSpaceKIFMM::count_strong_atoms() const
{
  bigint mine = 0, all = 0;
  for (int i = 0; i < atom->nlocal; ++i) mine += is_point(i);
  MPI_Allreduce(&mine, &all, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  return all;
}

double KSpaceKIFMM::force_prefactor() const
{
  // engine: grad = d/dx_i sum_j s_j G(x_i, x_j); potential energy U = c/2 sum_i s_i phi_i
  // coulomb/yukawa: c = qqrd2e (repulsive for like charges): F_i = -qqrd2e q_i grad_i
  // gravity: c = -G (attractive): F_i = +G m_i grad_i
  return kset.kernel == LongRangeKernel::Gravity ? kset.gravity_G : -qqrd2e;
}

double KSpaceKIFMM::energy_prefactor() const
{
  return kset.kernel == LongRangeKernel::Gravity ? -kset.gravity_G : qqrd2e;
}

// Engine exceptions (std::logic_error for input it refuses, std::runtime_error, std::bad_alloc)
// as LAMMPS errors on the rank that met them (the others may be waiting in a collective: as
// error->one, the run ends). LAMMPS's own exceptions (error->all with LAMMPS_EXCEPTIONS) are
// none of these and pass through.
template <class F> void KSpaceKIFMM::guarded(const char *what, F &&body)
{
  try {
    body();
  } catch (std::bad_alloc &) {
    error->one(FLERR, "kspace_style kifmm: out of memory in {} (step {}); fewer atoms per rank or a lower "
               "accuracy need less", what, update->ntimestep);
  } catch (std::logic_error &e) {
    error->one(FLERR, "kspace_style kifmm: {} stopped (step {}): {}", what, update->ntimestep, e.what());
  } catch (std::runtime_error &e) {
    error->one(FLERR, "kspace_style kifmm: {} stopped (step {}): {}", what, update->ntimestep, e.what());
  }
}

void KSpaceKIFMM::init()
{
  guarded("init", [this] { init_style_and_engine(); });
}

void KSpaceKIFMM::setup()
{
  guarded("the setup of the run", [this] { setup_run(); });
}

void KSpaceKIFMM::compute(int eflag, int vflag)
{
  guarded("the long-range evaluation", [&] { compute_step(eflag, vflag); });
}

void KSpaceKIFMM::init_style_and_engine()
{
  if (domain->dimension == 2)
    error->all(FLERR,
               "kspace_style kifmm does not support dimension 2: its kernels (coulomb, gravity, "
               "yukawa) are the 3-d ones");
  if (domain->triclinic)
    error->all(FLERR, "kspace_style kifmm does not support triclinic boxes");
  if (kset.kernel == LongRangeKernel::Gravity) {
    if (!atom->rmass_flag && !atom->mass)
      error->all(FLERR, "kspace_style kifmm kernel gravity requires per-atom or per-type masses");
  } else if (!atom->q_flag) {
    error->all(FLERR,
               "kspace_style kifmm kernel {} requires atom attribute q (atom_style charge, "
               "full, hybrid ... charge, or fix property/atom q)",
               kifmm_lammps::kernel_name(kset.kernel));
  }

  find_force_schedule();    // fix kifmm/stride: evaluations on a schedule
  find_rigid_bodies();    // fix clump/rigid: pairs inside a clump are left out
  qqrd2e = force->qqrd2e;
  scale = 1.0;
  if (kset.kernel != LongRangeKernel::Gravity) qsum_qsq(0);
  periodic_init();    // p p p: checks, net-charge warning (kspace_kifmm_periodic.cpp)
  dipole_init();      // atoms with dipole moments (kspace_kifmm_dipoles.cpp)

  // a coulomb pair style would count coulomb a second time (kifmm sums everything)
  if (force->pair && kset.kernel != LongRangeKernel::Gravity && comm->me == 0 &&
      (force->pair_match("coul", 0) || force->pair_match("born/coul", 0)))
    error->warning(FLERR,
                   "kspace_style kifmm computes the full coulomb sum; the coulomb part of pair "
                   "style {} is counted twice",
                   force->pair_style);
  // neighbor exclusions act on the pair style's neighbor lists, not on this full sum
  if (comm->me == 0) {
    const std::string excluded = unapplied_exclusions(lmp);
    if (!excluded.empty())
      error->warning(FLERR,
                     "kspace_style kifmm sums all pairs: neigh_modify exclude ({}) does not "
                     "apply to the long-range sum",
                     excluded);
  }

  kifmm::Options opt;
  double est = 0.0;
  kifmm::KernelSpec kernel;
  if (kset.kernel == LongRangeKernel::Yukawa) {
    kernel.type = kifmm::KernelType::Yukawa;
    kernel.kappa = kset.kappa;
  }
  if (kset.order > 0) {
    opt.order = kset.order;
    est = -1.0;
  } else {
    kifmm::Choice c = kifmm::choose_order(kernel, kset.accuracy, periodic);
    opt.order = c.order;
    est = c.measured_error;
    // a previous run of these settings measured which order meets the request: start there
    if (chosen_order > 0) opt.order = chosen_order;
  }
  // the tree holds only atoms of nonzero strength (zero-strength atoms are not gathered)
  const bigint nstrong = count_strong_atoms();
  if (kset.cache_dir == "none")
    opt.cache_dir.clear();
  else
    opt.cache_dir = kset.cache_dir.empty() ? default_cache_dir() : kset.cache_dir;
  // a missing cache directory is created (on rank 0); if that fails, memory only
  if (!opt.cache_dir.empty()) {
    std::string why = comm->me == 0 ? make_cache_dir(opt.cache_dir) : std::string();
    int failed = !why.empty();
    MPI_Bcast(&failed, 1, MPI_INT, 0, world);
    if (failed) {
      if (comm->me == 0)
        error->warning(FLERR,
                       "kspace_style kifmm: cannot create the operator cache directory {} ({}): "
                       "caching on disk is off, every new process computes the operators again",
                       opt.cache_dir, why);
      opt.cache_dir.clear();
    }
  }
  opt.periodic = periodic;
  if (dipoles) opt.near_pair_weight = kifmm::kDipolePairWeight;    // the tree choice for dipoles
  if (periodic) periodic_root(opt);    // the box: center, half-widths (kspace_kifmm_periodic.cpp)
  if (kset.grid > 0 && !periodic)
    error->all(FLERR, "kspace_modify kifmm grid {}: the single-level grid needs periodic boundaries "
                      "(boundary p p p)", kset.grid);
  // the tree (kifmm::plan_tree): a given leaf size (kspace_modify kifmm leaf); else the uniform
  // choice for this many atoms and, on one rank, the choice from the atom positions at the first
  // evaluation of the run (choose_tree_from_atoms); the single-level grid given (kspace_modify
  // kifmm grid K) or chosen with the tree (grid auto)
  tree_request = kifmm::TreeRequest{(std::size_t) nstrong, kset.leaf, kset.grid, distributed()};
  const kifmm::TreePlan plan = kifmm::plan_tree(opt, tree_request, engine ? &engine_options : nullptr);
  opt = plan.options;
  if (periodic) fit_periodic_box(opt);    // the octree in nearly cubic boxes, else a grid that fits
  const kifmm::TreeChoice &tree = plan.uniform;
  const bool grid_auto = periodic && kset.grid < 0;
  tree_choice_pending = plan.from_points;
  tune_pending = kset.tune;
  tuner = kifmm::TreeTuner();

  if (!engine || engine_options.order != opt.order || engine_options.leaf_size != opt.leaf_size ||
      engine_options.cache_dir != opt.cache_dir || engine_options.periodic != opt.periodic ||
      engine_options.periodic_grid != opt.periodic_grid || engine_options.near_pair_weight != opt.near_pair_weight) {
    engine = kifmm::make_evaluator(kernel, opt);
    reported_first_evaluation = false;
  }
  engine_options = engine->options();
  estimated_error = est;
  // order from the accuracy: measured on the atoms at the first evaluation, raised if needed
  verify_pending = est >= 0;
  if (est > kset.accuracy && comm->me == 0)
    error->warning(FLERR,
                   "kspace_style kifmm: the requested accuracy {:.3g} is below what the highest "
                   "calibrated order {} reaches ({:.3g} in the calibration); it is measured on the "
                   "atoms at the first evaluation",
                   kset.accuracy, opt.order, est);
  kcomm = std::make_unique<kifmm::MpiCommunicator>(world);

  // the end-of-run time breakdown is printed by an internal fix (fixes get post_run)
  if (modify->find_fix(timing_fix_id) < 0)
    modify->add_fix(std::string(timing_fix_id) + " all KIFMM/TIMING");

  if (comm->me == 0) {
    std::string mesg = "KIFMM initialization ...\n";
    mesg += fmt::format("  kernel = {}", kifmm_lammps::kernel_name(kset.kernel));
    if (kset.kernel == LongRangeKernel::Gravity) mesg += fmt::format(" (G = {:.8g})", kset.gravity_G);
    if (kset.kernel == LongRangeKernel::Yukawa) mesg += fmt::format(" (kappa = {:.8g})", kset.kappa);
    const bool grid_only = periodic && (slab || !kifmm::octree_fits_cell(engine_options.root_shape));
    if (tree_choice_pending && grid_only)
      mesg += fmt::format("\n  order = {}, single-level grid chosen from the atom positions at the first "
                          "evaluation (a box that is not nearly cubic: single-level grids, least "
                          "modelled cost; for {} uniformly spread atoms: {} cells)",
                          engine_options.order, nstrong, grid_cells_text(engine_options));
    else if (tree_choice_pending)
      mesg += fmt::format("\n  order = {}, {} chosen from the atom positions at the first "
                          "evaluation (least modelled cost of the actual trees{}; for {} uniformly "
                          "spread atoms, {} boundaries: leaf size {}, tree depth {})",
                          engine_options.order, grid_auto ? "leaf size or single-level grid" : "leaf size",
                          grid_auto ? " and grids" : "",
                          nstrong, periodic ? "periodic" : "open", tree.leaf_size, tree.depth);
    else if (grid_only)
      mesg += fmt::format("\n  order = {}", engine_options.order);
    else
      mesg += fmt::format("\n  order = {}, leaf size = {}", engine_options.order, engine_options.leaf_size);
    if (tree.depth >= 0 && !tree_choice_pending && !grid_only)
      mesg += fmt::format(" (tree depth {} for {} uniformly spread atoms, {} boundaries: least "
                          "modelled cost)",
                          tree.depth, nstrong, periodic ? "periodic" : "open");
    if (engine_options.periodic_grid > 0 && (kset.grid > 0 || !tree_choice_pending))
      mesg += fmt::format("\n  periodic single-level grid of {} cells ({})", grid_cells_text(engine_options),
                          kset.grid > 0 ? "kspace_modify kifmm grid"
                                        : fmt::format("for {} uniformly spread atoms: least modelled cost", nstrong));
    mesg += "\n";
    if (est >= 0)
      mesg += fmt::format("  requested relative force error = {:.3g}, calibrated = {:.3g}\n",
                          kset.accuracy, est);
    else
      mesg += "  order set by kspace_modify: error not estimated (use check to measure it)\n";
    mesg += fmt::format("  operator cache = {}\n",
                        engine_options.cache_dir.empty() ? "memory only" : engine_options.cache_dir);
    if (distributed())
      mesg += fmt::format("  MPI: distributed over {} ranks (global top tree, ghost atoms near each "
                          "rank's cells{}; no all-gather)\n",
                          comm->nprocs, periodic ? ", also through the periodic faces" : "");
    utils::logmesg(lmp, mesg);
  }
}

void KSpaceKIFMM::setup_run()
{
  warned_coincident = false;
  run_timing.reset();
  // memory the evaluations may use (read once per run; see check_memory)
  memory_limit_mb = 0;
  if (const char *env = std::getenv("KIFMM_MEMORY_LIMIT_MB")) {
    memory_limit_mb = std::atof(env);
  } else if (FILE *fp = fopen("/proc/meminfo", "r")) {
    char line[256];
    while (fgets(line, sizeof(line), fp))
      if (strncmp(line, "MemAvailable:", 13) == 0) memory_limit_mb = std::atof(line + 13) / 1024.0;
    fclose(fp);
  }
}

// Leaf size from the atom positions (no leaf size given): the engine builds the trees of a few
// candidate leaf sizes over these atoms and takes the one of least modelled cost
// (kifmm::choose_tree(kernel, options, n, xyz)); on several ranks over the stand-in of all
// ranks' atoms (kifmm::gather_layout, the same on every rank); once per run, at its first
// evaluation.
void KSpaceKIFMM::choose_tree_from_atoms()
{
  tree_choice_pending = false;
  std::size_t n = strength.size();
  kifmm::Options opt = engine->options();    // the periodic cell is its root (periodic_cell)
  const double t0 = MPI_Wtime();
  kifmm::TreeChoice c{opt.leaf_size, 0, 0.0, opt.periodic_grid};
  if (distributed()) {
    const kifmm::PointLayout layout = kifmm::gather_layout(engine->kernel(), opt, n, xyz.data(), *kcomm);
    n = layout.n;
    if (layout.xyz.empty()) return;
    c = kifmm::choose_tree_from_layout(engine->kernel(), tree_request, opt, layout);
  } else {
    if (n == 0) return;
    c = kifmm::choose_tree_from_points(engine->kernel(), tree_request, opt, n, xyz.data());
  }
  const double t_choice = MPI_Wtime() - t0;
  const int grid = opt.periodic_grid;
  if (opt.leaf_size != engine_options.leaf_size || grid != engine_options.periodic_grid) {
    engine = kifmm::make_evaluator(engine->kernel(), opt);
    engine_options = engine->options();
    reported_first_evaluation = false;
  }
  if (comm->me != 0) return;
  if (grid > 0)
    utils::logmesg(lmp,
                   "  KIFMM periodic single-level grid of {} cells{} for {} atoms (modelled {:.3g} s "
                   "per evaluation on one thread; choice {:.3g} s)\n",
                   grid_cells_text(engine_options), kset.grid < 0 ? " chosen from the atom positions" : "", n, c.cost, t_choice);
  else
    utils::logmesg(lmp,
                   "  KIFMM tree chosen from the positions of {} atoms{}: leaf size {} (tree depth {}, "
                   "modelled {:.3g} s per evaluation on one thread; choice {:.3g} s)\n",
                   n, distributed() ? " (their layout over all ranks)" : "", c.leaf_size, c.depth, c.cost, t_choice);
}

// Pairs at zero distance are excluded from the sum (never inf); say so once per run.
void KSpaceKIFMM::report_coincident_pairs(std::size_t local_pairs)
{
  if (warned_coincident) return;
  bigint mine = (bigint) local_pairs, total = 0;
  MPI_Allreduce(&mine, &total, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (total == 0) return;
  warned_coincident = true;
  if (comm->me == 0)
    error->warning(FLERR,
                   "kspace_style kifmm: {} source-target pairs of atoms at zero distance are "
                   "excluded from the long-range sum (step {})",
                   total, update->ntimestep);
}

// Refuse an evaluation whose memory estimate exceeds what the machine has, with the estimate,
// instead of failing inside the allocator. The limit is MemAvailable from /proc/meminfo, or
// KIFMM_MEMORY_LIMIT_MB when set (both read in setup()).
void KSpaceKIFMM::check_memory(std::size_t nsources)
{
  const double bytes =
      kifmm::estimate_memory_bytes(engine_options, nsources, engine->stats().operator_bytes);
  const double need_mb = bytes / 1048576.0;
  const double limit_mb = memory_limit_mb;
  int refuse = limit_mb > 0 && need_mb > limit_mb, any = 0;
  MPI_Allreduce(&refuse, &any, 1, MPI_INT, MPI_MAX, world);
  if (any)
    error->all(FLERR,
               "kspace_style kifmm: estimated memory {:.0f} MB for {} atoms at order {} exceeds "
               "the {:.0f} MB available on a rank; use fewer atoms per rank or a lower accuracy",
               need_mb, nsources, engine_options.order, limit_mb);
}

void KSpaceKIFMM::gather_points()
{
  const int nlocal = atom->nlocal;
  double **x = atom->x;
  index.clear();
  xyz.clear();
  strength.clear();
  moment.clear();
  for (int i = 0; i < nlocal; ++i) {
    const double s = strength_of(i);
    if (!std::isfinite(s) || !std::isfinite(x[i][0]) || !std::isfinite(x[i][1]) ||
        !std::isfinite(x[i][2]))
      error->one(FLERR, "kspace_style kifmm: atom {} has a non-finite {} or position",
                 atom->tag[i], kset.kernel == LongRangeKernel::Gravity ? "mass" : "charge");
    if (atom->mu_flag && !dipoles && (atom->mu[i][0] != 0.0 || atom->mu[i][1] != 0.0 || atom->mu[i][2] != 0.0))
      error->one(FLERR, "kspace_style kifmm: atom {} has a dipole moment, but none had one when the run was "
                 "set up (the sum includes dipoles only when some atom has a moment at the start of a run)",
                 atom->tag[i]);
    if (dipoles && !(std::isfinite(atom->mu[i][0]) && std::isfinite(atom->mu[i][1]) && std::isfinite(atom->mu[i][2])))
      error->one(FLERR, "kspace_style kifmm: atom {} has a non-finite dipole moment", atom->tag[i]);
    if (!is_point(i)) continue;    // zero strength (and no moment): neither source nor target
    index.push_back(i);
    xyz.insert(xyz.end(), {x[i][0], x[i][1], x[i][2]});
    strength.push_back(s);
    if (dipoles) moment.insert(moment.end(), {atom->mu[i][0], atom->mu[i][1], atom->mu[i][2]});
  }
}

void KSpaceKIFMM::evaluate_points(bool want_potential, double &comm_time, std::size_t &nsrc)
{
  if (dipoles) {
    evaluate_dipole_points(want_potential, comm_time, nsrc);
    return;
  }
  const std::size_t n = index.size();
  pot.assign(want_potential ? n : 0, 0.0);
  grad.assign(3 * n, 0.0);
  comm_time = 0;
  if (distributed()) {
    // each rank passes its own atoms (collective; ghosts are exchanged inside)
    check_memory(n);
    engine->evaluate_distributed(*kcomm, n, xyz.data(), strength.data(),
                                 want_potential ? pot.data() : nullptr, grad.data());
    comm_time = engine->stats().t_comm;
    nsrc = engine->stats().n_sources;
  } else {
    // one rank: its atoms are the sources and the targets
    nsrc = strength.size();
    check_memory(nsrc);
    if (nsrc > 0)
      engine->evaluate(nsrc, xyz.data(), strength.data(), n, xyz.data(),
                       want_potential ? pot.data() : nullptr, grad.data());
  }
  subtract_body_pairs(want_potential);
}

void KSpaceKIFMM::find_force_schedule()
{
  // (a second one is an error of fix kifmm/stride's init)
  schedule = nullptr;
  for (int i = 0; i < modify->nfix && !schedule; ++i)
    schedule = dynamic_cast<KIFMMForceSchedule *>(modify->fix[i]);
}

bool KSpaceKIFMM::distributed() const
{
  return comm->nprocs > 1;
}

void KSpaceKIFMM::compute_step(int eflag, int vflag)
{
  ev_init(eflag, vflag);
  energy = 0.0;
  for (double &v : virial) v = 0.0;

  // fix kifmm/stride: on skipped steps it adds the held forces (or none) and reports the last
  // energy/virial; EnergyOnly evaluates without adding forces; Evaluate stores the forces
  using Stride = KIFMMForceSchedule::Action;
  Stride action = Stride::Plain;
  if (schedule) {
    action = schedule->plan(eflag_global || vflag_global, eflag_atom || vflag_atom, vflag_global,
                            energy, virial, [this](int i) { return is_point(i); });
    if (action == Stride::Skip) return;
  }
  const bool keep = action == Stride::Evaluate && schedule->keeps_energy();
  const bool apply = action != Stride::EnergyOnly;
  const double fscale = schedule ? schedule->force_scale(action) : 1.0;

  // grow per-atom arrays if requested (as the KSPACE styles do)
  if (atom->nmax > maxeatom && eflag_atom) {
    maxeatom = atom->nmax;
    memory->destroy(eatom);
    memory->create(eatom, maxeatom, "kifmm:eatom");
  }
  if (atom->nmax > maxvatom && vflag_atom) {
    maxvatom = atom->nmax;
    memory->destroy(vatom);
    memory->create(vatom, maxvatom, 6, "kifmm:vatom");
  }
  if (eflag_atom)
    for (int i = 0; i < atom->nlocal; ++i) eatom[i] = 0.0;
  if (vflag_atom)
    for (int i = 0; i < atom->nlocal; ++i)
      for (int k = 0; k < 6; ++k) vatom[i][k] = 0.0;

  const double t_start = MPI_Wtime();
  gather_points();
  const std::size_t n = index.size();

  update_slab_extent();
  select_tuned_tree();
  if (periodic) periodic_cell();    // the box is the cell (it may have changed)
  if (tree_choice_pending) choose_tree_from_atoms();
  // induced dipoles first (kspace_kifmm_polarize.cpp); an energy-only evaluation of fix
  // kifmm/stride takes the dipoles of its last evaluation, with its held forces
  double t_polarize = 0;
  if (polarization && action != Stride::EnergyOnly) {
    t_polarize = MPI_Wtime();
    polarize_points();
    t_polarize = MPI_Wtime() - t_polarize;
  }
  const bool want_potential = eflag_global || eflag_atom || keep || (periodic && vflag_global);
  prepare_rigid_bodies();
  check_pebble_dipoles();
  double comm_time = 0;
  std::size_t nsrc = 0;    // sources of all ranks (same value on every rank)
  const double t_evaluation = MPI_Wtime();
  evaluate_points(want_potential, comm_time, nsrc);
  const double evaluation_seconds = MPI_Wtime() - t_evaluation - engine->stats().t_precompute;
  if (verify_pending) verify_accuracy(want_potential, comm_time, nsrc);
  tune_tree(evaluation_seconds, want_potential, comm_time, nsrc);
  const kifmm::Stats no_work;
  const kifmm::Stats &phases = nsrc > 0 || distributed() ? engine->stats() : no_work;

  double **f = atom->f;
  const double cf = force_prefactor(), ce = energy_prefactor();
  double e_local = 0.0;
  double v_local[6] = {0, 0, 0, 0, 0, 0};
  if (action == Stride::Evaluate) schedule->begin_evaluation();
  for (std::size_t k = 0; k < n; ++k) {
    const int i = index[k];
    double fk[3], tk[3];
    point_force(k, cf, fk, tk);
    const double fx = fk[0], fy = fk[1], fz = fk[2];
    if (apply) {
      f[i][0] += fscale * fx;
      f[i][1] += fscale * fy;
      f[i][2] += fscale * fz;
      if (dipoles)
        for (int d = 0; d < 3; ++d) atom->torque[i][d] += fscale * tk[d];
    }
    if (action == Stride::Evaluate) schedule->store(i, fk, dipoles ? tk : nullptr, &xyz[3 * k]);
    if (want_potential) {
      const double e = point_energy(k, ce);
      e_local += e;
      if (eflag_atom) eatom[i] += e;
    }
    if (vflag_global || keep) {
      // open system: W_ab = sum_i x_ia F_ib (equal to the pairwise sum_{i<j} r_ij,a F_ij,b)
      const double *xi = &xyz[3 * k];
      v_local[0] += xi[0] * fx;
      v_local[1] += xi[1] * fy;
      v_local[2] += xi[2] * fz;
      v_local[3] += xi[0] * fy;
      v_local[4] += xi[0] * fz;
      v_local[5] += xi[1] * fz;
    }
  }
  // kspace energy and virial are global values (LAMMPS's computes add them after their own
  // reduction over ranks), as in the KSPACE styles
  if (eflag_global || keep) MPI_Allreduce(&e_local, &energy, 1, MPI_DOUBLE, MPI_SUM, world);
  if (vflag_global || keep) MPI_Allreduce(v_local, virial, 6, MPI_DOUBLE, MPI_SUM, world);
  if (dipoles) {
    if (vflag_global || keep || vflag_atom) dipole_virial(cf, vflag_global || keep, vflag_atom);
  } else {
    const bool tensor = periodic_tensor();
    if (periodic && !tensor && (vflag_global || keep)) periodic_virial(e_local, cf);
    if (vflag_atom && periodic && !tensor)
      error->all(FLERR, "kspace_style kifmm: per-atom virial (compute stress/atom) with periodic boundaries "
                 "needs 'kspace_modify pressure/scalar no' (the default)");
    if (tensor && (vflag_global || keep || vflag_atom)) periodic_tensor_virial(cf, vflag_global || keep, vflag_atom);
    if (vflag_atom && !periodic && nsrc > 0) {
      double center[3] = {0, 0, 0};
      per_atom_virial(cf, center);
    }
  }
  if (action == Stride::Evaluate) schedule->end_evaluation(energy, virial);

  run_timing.add(phases, comm_time, MPI_Wtime() - t_start, n,
                 distributed() ? engine->stats().comm_bytes : 0, t_polarize);
  if (!reported_first_evaluation) report_first_evaluation();
  report_coincident_pairs(nsrc > 0 ? phases.coincident_pairs : 0);
  if (kset.check_every > 0 && update->ntimestep % kset.check_every == 0) check_error();
}

// Per-atom virial v_i,ab = 1/2 sum_j (x_i - x_j)_a F_ij,b, origin independent, as LAMMPS's pair
// styles tally it: the engine's (kifmm::point_virial: three more gradient evaluations, done only
// when a compute asks) without the pairs inside rigid bodies.
void KSpaceKIFMM::per_atom_virial(double cf, double center[3])
{
  const std::size_t n = index.size();
  std::vector<double> w(6 * n), u(3 * n);
  kifmm::point_virial(*engine, distributed() ? kcomm.get() : nullptr, n, xyz.data(),
                      strength.data(), grad.data(), cf, w.data(), center);
  for (std::size_t k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) u[3 * k + a] = xyz[3 * k + a] - center[a];
  add_body_pair_virial(cf, u.data(), w.data());
  for (std::size_t k = 0; k < n; ++k)
    for (int c = 0; c < 6; ++c) vatom[index[k]][c] += w[6 * k + c];
}

// The pairs inside rigid bodies are not in the sum: grad has lost their gradient o (the
// engine's virial formula used offset_a times grad: add offset_a o_b back) and their pair virial
// 1/2 cf s T_ab goes. offset: per point, the origin the engine's formula measured x from; null
// when grad still has the pairs (dipoles: the formula gave their virial, which goes).
void KSpaceKIFMM::add_body_pair_virial(double cf, const double *offset, double *w) const
{
  if (point_body.empty()) return;
  const int row[3][3] = {{4, 7, 8}, {7, 5, 9}, {8, 9, 6}};    // pair virial T_ab in body_pairs
  const int slot[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};   // LAMMPS order xx yy zz xy xz yz
  for (std::size_t k = 0; k < index.size(); ++k) {
    if (!point_body[k]) continue;
    const double *o = &body_pairs[(std::size_t) KIFMMRigidBodies::nvalues * k];
    const double s = strength[k];
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b)
        w[6 * k + slot[a][b]] += 0.5 * cf * s * ((offset ? offset[3 * k + a] * o[b] : 0.0) - o[row[a][b]]);
  }
}

void KSpaceKIFMM::report_first_evaluation()
{
  reported_first_evaluation = true;
  const kifmm::Stats &s = engine->stats();
  if (comm->me == 0 && engine_options.periodic_grid > 0)
    utils::logmesg(lmp,
                   "  KIFMM first evaluation: {} sources, single-level grid of {} cells, {} "
                   "coincident pairs excluded\n"
                   "  precompute {:.3g} s, operators and grid kernels {:.3g} MB, cells {:.3g} MB\n",
                   s.n_sources, grid_cells_text(engine->options()), s.coincident_pairs, s.t_precompute,
                   s.operator_bytes / 1048576.0, s.tree_bytes / 1048576.0);
  else if (comm->me == 0)
    utils::logmesg(lmp,
                   "  KIFMM first evaluation: {} sources, tree depth {}, {} cells, {} leaves, "
                   "{} coincident pairs excluded\n"
                   "  precompute {:.3g} s, operators {:.3g} MB, tree {:.3g} MB\n",
                   s.n_sources, s.depth, s.n_cells, s.n_leaves, s.coincident_pairs,
                   s.t_precompute, s.operator_bytes / 1048576.0, s.tree_bytes / 1048576.0);
  if (distributed()) {
    // load and halo of the distributed evaluation, min/avg/max over ranks
    double mine[4] = {(double) index.size(), (double) s.n_ghosts, (double) s.comm_bytes, (double) s.let_cells};
    double lo[4], hi[4], sum[4];
    MPI_Allreduce(mine, lo, 4, MPI_DOUBLE, MPI_MIN, world);
    MPI_Allreduce(mine, hi, 4, MPI_DOUBLE, MPI_MAX, world);
    MPI_Allreduce(mine, sum, 4, MPI_DOUBLE, MPI_SUM, world);
    const int np = comm->nprocs;
    if (comm->me == 0)
      utils::logmesg(lmp,
                     "  KIFMM ranks (min/avg/max): atoms {:.0f}/{:.1f}/{:.0f}, ghost atoms "
                     "{:.0f}/{:.1f}/{:.0f}, locally essential tree cells {:.0f}/{:.1f}/{:.0f}, bytes "
                     "sent {:.0f}/{:.0f}/{:.0f}; top tree level {}\n",
                     lo[0], sum[0] / np, hi[0], lo[1], sum[1] / np, hi[1], lo[3], sum[3] / np, hi[3], lo[2],
                     sum[2] / np, hi[2], s.top_level);
  }
}

const kifmm::Stats &KSpaceKIFMM::engine_stats() const
{
  return engine->stats();
}

double KSpaceKIFMM::memory_usage()
{
  double bytes = (double) (xyz.capacity() + strength.capacity() + pot.capacity() +
                           grad.capacity()) * sizeof(double) +
      (double) index.capacity() * sizeof(int);
  if (engine) bytes += (double) (engine->stats().operator_bytes + engine->stats().tree_bytes);
  bytes += (double) maxeatom * sizeof(double) + (double) maxvatom * 6 * sizeof(double);
  return bytes;
}
