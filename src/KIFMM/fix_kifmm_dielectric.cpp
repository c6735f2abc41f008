// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "fix_kifmm_dielectric.h"

#include "kifmm.h"

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "update.h"
#include "utils.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <vector>
#include <mpi.h>

using namespace LAMMPS_NS;

FixKIFMMDielectric::FixKIFMMDielectric(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  bool have_eps = false, have_field = false;
  for (int iarg = 3; iarg < narg;) {
    const std::string key = arg[iarg];
    const int nval = key == "field" ? 3 : 1;
    if (iarg + nval >= narg) error->all(FLERR, "fix kifmm/dielectric: keyword {} needs {} value(s)", key, nval);
    if (key == "permittivity") {
      permittivity = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      if (!(permittivity > 0)) error->all(FLERR, "fix kifmm/dielectric: permittivity {} must be positive", arg[iarg + 1]);
      have_eps = true;
    } else if (key == "field") {
      for (int d = 0; d < 3; ++d) field[d] = utils::numeric(FLERR, arg[iarg + 1 + d], false, lmp);
      have_field = true;
    } else if (key == "degree") {
      degree = utils::inumeric(FLERR, arg[iarg + 1], false, lmp);
      if (degree < 1 || degree > 40) error->all(FLERR, "fix kifmm/dielectric: degree {} must be in 1 .. 40", degree);
    } else if (key == "tol") {
      tol = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      if (!(tol > 0 && tol < 1)) error->all(FLERR, "fix kifmm/dielectric: tol {} must be in (0, 1)", arg[iarg + 1]);
    } else if (key == "order") {
      order = utils::inumeric(FLERR, arg[iarg + 1], false, lmp);
      if (order < 3 || order > 14) error->all(FLERR, "fix kifmm/dielectric: order {} must be in 3 .. 14", order);
    } else if (key == "every") {
      every = utils::inumeric(FLERR, arg[iarg + 1], false, lmp);
      if (every < 1) error->all(FLERR, "fix kifmm/dielectric: every {} must be positive", every);
    } else if (key == "overlap") {
      const std::string v = arg[iarg + 1];
      if (v != "touch" && v != "error") error->all(FLERR, "fix kifmm/dielectric: overlap must be touch or error, not '{}'", v);
      touch_overlaps = v == "touch";
    } else if (key == "shrink") {
      shrink = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      if (!(shrink >= 0 && shrink < 0.5)) error->all(FLERR, "fix kifmm/dielectric: shrink {} must be in [0, 0.5)", arg[iarg + 1]);
    } else {
      error->all(FLERR, "fix kifmm/dielectric: unknown keyword '{}'", key);
    }
    iarg += 1 + nval;
  }
  if (!have_eps) error->all(FLERR, "fix kifmm/dielectric: the permittivity is missing (permittivity EPS)");
  if (!have_field) error->all(FLERR, "fix kifmm/dielectric: the field is missing (field Ex Ey Ez)");
  scalar_flag = 1;    // the polarization energy
  extscalar = 1;
  energy_global_flag = 1;
  vector_flag = 1;    // GMRES steps, residual, nodes with a graded quadrature, overlapping pairs
  size_vector = 4;
  extvector = 0;
  global_freq = 1;
  peratom_flag = 1;    // the induced dipoles
  size_peratom_cols = 3;
  peratom_freq = 1;
  dynamic_group_allow = 0;
  kifmm::Options o;
  o.order = order;
  evaluator = kifmm::make_evaluator(kifmm::KernelSpec{}, o);
}

FixKIFMMDielectric::~FixKIFMMDielectric()
{
  memory->destroy(dipole);
}

int FixKIFMMDielectric::setmask()
{
  return FixConst::POST_FORCE | FixConst::MIN_POST_FORCE;
}

void FixKIFMMDielectric::init()
{
  if (!atom->radius_flag) error->all(FLERR, "fix kifmm/dielectric needs atom radii (atom_style sphere)");
  if (domain->xperiodic || domain->yperiodic || domain->zperiodic)
    error->all(FLERR, "fix kifmm/dielectric: open boundaries only (boundary f, s or m along x, y and z)");
  if (utils::strmatch(update->integrate_style, "^respa"))
    error->all(FLERR, "fix kifmm/dielectric cannot be used with run_style respa");
}

void FixKIFMMDielectric::setup(int)
{
  solve();
  apply();
}

void FixKIFMMDielectric::min_setup(int vflag)
{
  setup(vflag);
}

void FixKIFMMDielectric::min_post_force(int)
{
  solve();
  apply();
}

void FixKIFMMDielectric::post_force(int)
{
  if (update->ntimestep - last_solve >= every) solve();
  apply();
}

// every rank: all spheres of the group in the order of their atom IDs, solved; their forces,
// torques and dipoles in LAMMPS units kept by atom ID
void FixKIFMMDielectric::solve()
{
  const int nlocal = atom->nlocal;
  std::vector<double> mine;    // id, x, y, z, radius
  for (int i = 0; i < nlocal; ++i)
    if (atom->mask[i] & groupbit) {
      const double rec[5] = {(double) atom->tag[i], atom->x[i][0], atom->x[i][1], atom->x[i][2], atom->radius[i]};
      mine.insert(mine.end(), rec, rec + 5);
    }
  int count = (int) mine.size();
  std::vector<int> counts(comm->nprocs), displs(comm->nprocs, 0);
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, world);
  for (int p = 1; p < comm->nprocs; ++p) displs[p] = displs[p - 1] + counts[p - 1];
  std::vector<double> all(displs.back() + counts.back());
  MPI_Allgatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, world);
  const std::size_t n = all.size() / 5;
  std::vector<std::size_t> order_by_id(n);
  std::iota(order_by_id.begin(), order_by_id.end(), 0);
  std::sort(order_by_id.begin(), order_by_id.end(), [&](std::size_t a, std::size_t b) { return all[5 * a] < all[5 * b]; });
  std::vector<double> center(3 * n), radius(n), eps(n, permittivity / force->dielectric);
  ids.assign(n, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const double *r = &all[5 * order_by_id[k]];
    ids[k] = (tagint) r[0];
    for (int d = 0; d < 3; ++d) center[3 * k + d] = r[1 + d];
    radius[k] = r[4] * (1.0 - shrink);
    if (!(radius[k] > 0)) error->all(FLERR, "fix kifmm/dielectric: atom {} has no positive radius", ids[k]);
  }

  // the field in force / charge units, as fix efield applies it
  const double qe2f = force->qe2f, C = force->qqrd2e;
  const double E0[3] = {qe2f * field[0], qe2f * field[1], qe2f * field[2]};
  kifmm::DielectricSphereOptions opt;
  opt.degree = degree;
  opt.tolerance = tol;
  opt.touch_overlaps = touch_overlaps;
  kifmm::DielectricSphereSolve s;
  try {
    s = kifmm::polarize_dielectric_spheres(n > 0 ? evaluator.get() : nullptr, n, center.data(), radius.data(), eps.data(),
                                           E0, opt);
  } catch (const std::invalid_argument &e) {
    std::size_t a = 0, b = 0;
    if (std::sscanf(e.what(), "dielectric spheres: spheres %zu and %zu overlap", &a, &b) == 2 && a < n && b < n)
      error->all(FLERR,
                 "fix kifmm/dielectric: the spheres of atoms {} and {} overlap (the surface equation needs "
                 "separate spheres; keyword overlap touch solves overlapping spheres as touching)",
                 ids[a], ids[b]);
    error->all(FLERR, "fix kifmm/dielectric: {}", e.what());
  }
  last_solve = update->ntimestep;
  iterations = s.iterations;
  residual = s.residual;
  near_rows = (double) s.near_rows;
  overlapping_pairs = (double) s.overlapping_pairs;
  if (!s.converged && comm->me == 0)
    error->warning(FLERR, "fix kifmm/dielectric: GMRES stopped at relative residual {:.3g} (tol {:.3g}) at step {}",
                   s.residual, tol, update->ntimestep);

  // forces, torques and dipoles in LAMMPS units: the surface charge sigma / (4 pi C)
  const double scale = 1.0 / (4.0 * M_PI * C);
  sphere_force.resize(3 * n);
  sphere_torque.resize(3 * n);
  sphere_dipole.resize(3 * n);
  energy = 0;
  for (std::size_t k = 0; k < 3 * n; ++k) {
    sphere_force[k] = scale * s.force[k];
    sphere_torque[k] = scale * s.torque[k];
    sphere_dipole[k] = scale * s.dipole[k];
    energy -= 0.5 * sphere_dipole[k] * E0[k % 3];
  }
}

// the kept forces and torques on the local atoms of the group (by atom ID), their dipoles in
// the per-atom array
void FixKIFMMDielectric::apply()
{
  const int nlocal = atom->nlocal;
  if (atom->nmax > nmax) {
    nmax = atom->nmax;
    memory->destroy(dipole);
    memory->create(dipole, nmax, 3, "kifmm/dielectric:dipole");
    array_atom = dipole;
  }
  for (int i = 0; i < nlocal; ++i) {
    for (int d = 0; d < 3; ++d) dipole[i][d] = 0.0;
    if (!(atom->mask[i] & groupbit)) continue;
    const auto it = std::lower_bound(ids.begin(), ids.end(), atom->tag[i]);
    if (it == ids.end() || *it != atom->tag[i]) continue;    // joined the group after the last solve
    const std::size_t k = it - ids.begin();
    for (int d = 0; d < 3; ++d) {
      atom->f[i][d] += sphere_force[3 * k + d];
      if (atom->torque_flag) atom->torque[i][d] += sphere_torque[3 * k + d];
      dipole[i][d] = sphere_dipole[3 * k + d];
    }
  }
}

double FixKIFMMDielectric::compute_scalar()
{
  return energy;
}

double FixKIFMMDielectric::compute_vector(int k)
{
  return k == 0 ? iterations : k == 1 ? residual : k == 2 ? near_rows : overlapping_pairs;
}

double FixKIFMMDielectric::memory_usage()
{
  return (3.0 * nmax + 9.0 * ids.size()) * sizeof(double) + ids.size() * sizeof(tagint);
}
