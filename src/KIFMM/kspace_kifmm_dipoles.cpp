// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point dipoles in kspace_style kifmm (atoms with a dipole moment mu: atom_style dipole,
// hybrid sphere dipole; induced ones of fix kifmm/polarize): the engine's evaluate_dipoles
// gives at every atom the potential phi of all charges and dipoles, its gradient g and its
// second derivatives h; then
//   F_i   = -qqrd2e (q_i g_i + h_i mu_i)        (q E + (mu . grad) E)
//   tau_i = -qqrd2e mu_i x g_i                  (mu x E)
//   U     = qqrd2e / 2 sum_i (q_i phi_i + mu_i . g_i)
// as pair lj/cut/dipole/cut sums them with a cutoff. Open boundaries, and p p p with kernel
// coulomb (tin-foil, as ewald/disp sums dipoles); on several ranks the evaluation is distributed
// (each rank passes its own atoms: evaluate_dipoles_distributed), as are the virial and the
// error check; no rank gathers the atoms of all others. The measured error covers forces and torques (sampled against the exact sum;
// periodic: an Ewald sum).
// Rigid clumps (fix clump/rigid): the pairs of charges inside a clump are left out as without
// dipoles (their part of the gradient and potential, body_pairs, comes off q_i's force and
// energy only); the induced dipoles of pebbles (fix kifmm/polarize) see every field, that of
// their own clump too, and act on every charge and dipole. Those pairs are not constant in the
// body frame, and their forces and torques cancel in the clump's net force and torque.
// Permanent dipoles on pebbles are an error.
#include "kspace_kifmm.h"

#include "kifmm_polarization.h"
#include "kifmm_rigid_bodies.h"

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "update.h"

#include <cmath>
#include <mpi.h>

using namespace LAMMPS_NS;
using kifmm_lammps::LongRangeKernel;

namespace {
bool has_moment(const double *mu)
{
  return mu[0] != 0.0 || mu[1] != 0.0 || mu[2] != 0.0;
}
// force q gq + h mu and torque mu x g of a point (without the prefactor -qqrd2e); gq: the
// gradient the charge feels (g without the charges of its own clump)
void dipole_force_torque(double q, const double *mu, const double *gq, const double *g, const double *h,
                         double f[3], double t[3])
{
  f[0] = q * gq[0] + h[0] * mu[0] + h[3] * mu[1] + h[4] * mu[2];
  f[1] = q * gq[1] + h[3] * mu[0] + h[1] * mu[1] + h[5] * mu[2];
  f[2] = q * gq[2] + h[4] * mu[0] + h[5] * mu[1] + h[2] * mu[2];
  t[0] = mu[1] * g[2] - mu[2] * g[1];
  t[1] = mu[2] * g[0] - mu[0] * g[2];
  t[2] = mu[0] * g[1] - mu[1] * g[0];
}
}    // namespace

// Dipole mode when the atom style has dipole moments and some atom's is not zero, or a fix gives
// atoms induced dipoles (fix kifmm/polarize). Checked at init: what the dipole sum does not
// cover yet is an error naming it.
void KSpaceKIFMM::dipole_init()
{
  dipoles = false;
  find_polarization();    // fix kifmm/polarize: induced dipoles
  if (!atom->mu_flag) return;
  int mine = 0, any = 0;
  for (int i = 0; i < atom->nlocal && !mine; ++i) mine = has_moment(atom->mu[i]);
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, world);
  if (!any && !polarization) return;
  dipoles = true;
  if (kset.kernel == LongRangeKernel::Gravity)
    error->all(FLERR, "kspace_style kifmm kernel gravity has no dipoles: the atoms have dipole moments (mu); "
                      "use kernel coulomb or yukawa");
  if (!atom->torque_flag)
    error->all(FLERR, "kspace_style kifmm: atoms with dipole moments need atom attribute torque "
                      "(atom_style hybrid sphere dipole)");
}

// Rigid clumps with dipoles (after prepare_rigid_bodies): a pebble may carry an induced dipole
// (fix kifmm/polarize), not a permanent one.
void KSpaceKIFMM::check_pebble_dipoles()
{
  if (!dipoles || point_body.empty()) return;
  for (std::size_t k = 0; k < index.size(); ++k) {
    const int i = index[k];
    if (point_body[k] && has_moment(atom->mu[i]) && !(polarization && polarization->polarizable(i)))
      error->one(FLERR,
                 "kspace_style kifmm: atom {} of clump {} has a permanent dipole moment; pebbles of rigid clumps "
                 "(fix clump/rigid) may carry induced dipoles (fix kifmm/polarize) only",
                 atom->tag[i], point_body[k]);
  }
}

// dipole mode: the gradient the charge of point k feels, g without its own clump's charges
void KSpaceKIFMM::charge_gradient(std::size_t k, const double *g, double gq[3]) const
{
  const bool in_body = !point_body.empty() && point_body[k];
  for (int d = 0; d < 3; ++d)
    gq[d] = g[d] - (in_body ? body_pairs[(std::size_t) KIFMMRigidBodies::nvalues * k + d] : 0.0);
}

bool KSpaceKIFMM::is_point(int i) const
{
  if (strength_of(i) != 0.0) return true;
  return dipoles && (has_moment(atom->mu[i]) || (polarization && polarization->polarizable(i)));
}

void KSpaceKIFMM::evaluate_dipole_points(bool want_potential, double &comm_time, std::size_t &nsrc)
{
  const std::size_t n = index.size();
  pot.assign(want_potential ? n : 0, 0.0);
  grad.assign(3 * n, 0.0);
  hess.assign(6 * n, 0.0);
  comm_time = 0;
  if (distributed()) {
    // each rank passes its own atoms (collective; ghosts are exchanged inside)
    check_memory(n);
    engine->evaluate_dipoles_distributed(*kcomm, n, xyz.data(), strength.data(), moment.data(),
                                         want_potential ? pot.data() : nullptr, grad.data(), hess.data());
    comm_time = engine->stats().t_comm;
    nsrc = engine->stats().n_sources;
  } else {
    nsrc = strength.size();
    check_memory(nsrc);
    if (nsrc > 0)
      engine->evaluate_dipoles(nsrc, xyz.data(), strength.data(), moment.data(), n, xyz.data(),
                               want_potential ? pot.data() : nullptr, grad.data(), hess.data());
  }
}

void KSpaceKIFMM::point_force(std::size_t k, double cf, double f[3], double t[3]) const
{
  point_force(k, cf, &grad[3 * k], dipoles ? &hess[6 * k] : nullptr, f, t);
}

void KSpaceKIFMM::point_force(std::size_t k, double cf, const double *g, const double *h, double f[3],
                              double t[3]) const
{
  const double s = strength[k];
  if (!dipoles) {
    for (int d = 0; d < 3; ++d) f[d] = cf * s * g[d], t[d] = 0.0;
    return;
  }
  double gq[3];
  charge_gradient(k, g, gq);
  dipole_force_torque(s, &moment[3 * k], gq, g, h, f, t);
  for (int d = 0; d < 3; ++d) f[d] *= cf, t[d] *= cf;
}

double KSpaceKIFMM::point_energy(std::size_t k, double ce) const
{
  double e = strength[k] * pot[k];
  if (dipoles) {
    // (without dipoles the clump's pairs are already out of pot)
    if (!point_body.empty() && point_body[k])
      e -= strength[k] * body_pairs[(std::size_t) KIFMMRigidBodies::nvalues * k + 3];
    for (int d = 0; d < 3; ++d) e += moment[3 * k + d] * grad[3 * k + d];
  }
  return 0.5 * ce * e;
}

// Virial of charges and dipoles, global (virial[6]; open boundaries: the sum of x_i F_i that
// compute() made) and/or per atom (vatom): 1/2 sum over pairs (and images) of (x_i - x_j)_a F_ij,b (kifmm::dipole_point_virial, periodic:
// kifmm::periodic_dipole_point_virial on the single-level grid), without the pairs of charges
// inside rigid clumps. The torques make it unsymmetric; xy is r_x F_y as pair
// lj/cut/dipole/cut tallies it.
void KSpaceKIFMM::dipole_virial(double cf, bool global, bool peratom)
{
  global = global && periodic;    // open boundaries: sum_i x_i F_i, already in virial
  if (!global && !peratom) return;
  const std::size_t n = index.size();
  std::vector<double> w(6 * n);
  const double center[3] = {0.5 * (domain->boxlo[0] + domain->boxhi[0]), 0.5 * (domain->boxlo[1] + domain->boxhi[1]),
                            0.5 * (domain->boxlo[2] + domain->boxhi[2])};
  const double *x = xyz.data(), *q = strength.data(), *mu = moment.data();
  if (distributed()) {    // every rank passes its own points (collective)
    if (periodic)
      kifmm::periodic_dipole_point_virial(virial_evaluator(), *kcomm, n, x, q, mu, grad.data(), hess.data(), cf,
                                          w.data());
    else
      kifmm::dipole_point_virial(*engine, *kcomm, n, x, q, mu, grad.data(), hess.data(), cf, w.data(), center);
  } else if (n > 0) {
    if (periodic)
      kifmm::periodic_dipole_point_virial(virial_evaluator(), n, x, q, mu, n, x, q, mu, grad.data(), hess.data(), cf,
                                          w.data());
    else
      kifmm::dipole_point_virial(*engine, n, x, q, mu, n, x, q, mu, grad.data(), hess.data(), cf, w.data(), center);
  }
  add_body_pair_virial(cf, nullptr, w.data());    // grad has all pairs: no offset term
  store_point_virial(w, global, peratom);
}

// Sampled error of forces and torques against the exact sum over all ranks' points.
KSpaceKIFMM::MeasuredError KSpaceKIFMM::measure_dipole_error(int nsamples)
{
  const std::size_t n = index.size();
  bigint nmine = (bigint) n, ntotal = 0;
  MPI_Allreduce(&nmine, &ntotal, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  const double nall = (double) ntotal;
  const unsigned long long seed = 1234567ULL + 7919ULL * (unsigned long long) update->ntimestep;
  std::vector<std::size_t> mine(n);
  for (std::size_t k = 0; k < n; ++k) mine[k] = k;
  const std::size_t want = nall > 0 ? (std::size_t) std::ceil(nsamples * (double) n / nall) : 0;
  const std::vector<std::size_t> sample =
      kifmm::sample_without_replacement(std::move(mine), want, seed + 104729ULL * (unsigned long long) comm->me);
  const std::size_t m = sample.size();
  std::vector<double> txyz(3 * m), g(3 * m), h(6 * m);
  for (std::size_t s = 0; s < m; ++s)
    for (int d = 0; d < 3; ++d) txyz[3 * s + d] = xyz[3 * sample[s] + d];
  // (several ranks: every rank sums its own sources at the samples of all ranks)
  kifmm::exact_dipole_field(*engine, distributed() ? kcomm.get() : nullptr, n, xyz.data(), strength.data(),
                            moment.data(), m, txyz.data(), g.data(), h.data());
  // sums: force diff2, ref2, all evaluated force2; torque the same
  double sums[6] = {0, 0, 0, 0, 0, 0}, tot[6];
  double f[3], t[3], fe[3], te[3];
  for (std::size_t k = 0; k < n; ++k) {
    point_force(k, 1.0, f, t);
    for (int d = 0; d < 3; ++d) sums[2] += f[d] * f[d], sums[5] += t[d] * t[d];
  }
  for (std::size_t s = 0; s < m; ++s) {
    const std::size_t k = sample[s];
    point_force(k, 1.0, f, t);
    double gq[3];
    charge_gradient(k, &g[3 * s], gq);    // the exact sum has the clump's pairs of charges too
    dipole_force_torque(strength[k], &moment[3 * k], gq, &g[3 * s], &h[6 * s], fe, te);
    for (int d = 0; d < 3; ++d) {
      sums[0] += (f[d] - fe[d]) * (f[d] - fe[d]);
      sums[1] += fe[d] * fe[d];
      sums[3] += (t[d] - te[d]) * (t[d] - te[d]);
      sums[4] += te[d] * te[d];
    }
  }
  MPI_Allreduce(sums, tot, 6, MPI_DOUBLE, MPI_SUM, world);
  bigint ms = (bigint) m, ms_all = 0;
  MPI_Allreduce(&ms, &ms_all, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  MeasuredError e;
  e.natoms = ms_all;
  if (ms_all > 0) {
    e.atoms = kifmm::sampled_relative_error(tot[0], tot[1], (double) ms_all, nall, tot[2]);
    if (tot[4] > 0 || tot[3] > 0) e.torques = kifmm::sampled_relative_error(tot[3], tot[4], (double) ms_all, nall, tot[5]);
  }
  return e;
}
