// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Measured error of kspace_style kifmm: the evaluated forces of a random sample against the
// exact sum (open: direct sum over all atoms; periodic: Ewald sum, in large boxes the engine at
// order 14, kifmm::reference_order), on what the integrator uses:
// the forces of free atoms, and the net force and torque of each rigid clump (fix clump/rigid;
// the forces inside a clump cancel there, so they are not what needs to be accurate).
// Used by `kspace_modify kifmm check` and, at the first evaluation of a run whose order comes
// from the requested accuracy, to raise the order until the request is met.
#include "kspace_kifmm.h"

#include "kifmm_rigid_bodies.h"

#include "comm.h"
#include "error.h"
#include "input.h"
#include "update.h"
#include "variable.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <mpi.h>
#include <random>

using namespace LAMMPS_NS;

namespace {
const char *error_variable = "kifmm_error";

// uniform in [0, 1) from a body ID and a seed (the same on every rank)
double body_hash(tagint tag, unsigned long long seed)
{
  unsigned long long z = (unsigned long long) tag * 0x9E3779B97F4A7C15ULL + seed;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return (double) (z >> 11) * 0x1.0p-53;
}

}    // namespace

double KSpaceKIFMM::MeasuredError::worst() const
{
  return std::max(std::max(atoms, torques), std::max(clump_force, clump_torque));
}

KSpaceKIFMM::MeasuredError KSpaceKIFMM::measure_error(int nsamples)
{
  if (dipoles) return measure_dipole_error(nsamples);    // forces and torques (kspace_kifmm_dipoles.cpp)
  const std::size_t n = index.size();
  const bool with_bodies = !point_body.empty();
  auto is_free = [&](std::size_t k) { return !with_bodies || point_body[k] == 0; };

  // how many free atoms and clumps there are (clumps: each pebble counts 1 / its clump's size)
  double mine[2] = {0, 0}, all[2];
  for (std::size_t k = 0; k < n; ++k) {
    if (is_free(k))
      mine[0] += 1;
    else
      mine[1] += point_clump_weight[k];
  }
  MPI_Allreduce(mine, all, 2, MPI_DOUBLE, MPI_SUM, world);

  // the sample: free atoms at random (without replacement), clumps by a hash of their ID (all
  // their pebbles)
  const unsigned long long seed = 1234567ULL + 7919ULL * (unsigned long long) update->ntimestep;
  std::vector<std::size_t> sample;
  if (all[0] > 0 && mine[0] > 0) {
    std::vector<std::size_t> free_points;
    for (std::size_t k = 0; k < n; ++k)
      if (is_free(k)) free_points.push_back(k);
    const std::size_t want = (std::size_t) std::ceil((double) nsamples * mine[0] / all[0]);
    sample = kifmm::sample_without_replacement(std::move(free_points), want,
                                               seed + 104729ULL * (unsigned long long) comm->me);
  }
  const double p_clump = all[1] > 0 ? std::min(1.0, nsamples / all[1]) : 0.0;
  for (std::size_t k = 0; k < n; ++k)
    if (!is_free(k) && body_hash(point_body[k], seed) < p_clump) sample.push_back(k);

  std::vector<double> exact;
  exact_gradient_at(sample, exact);

  // free atoms: their forces; clumps: net force and torque, summed over ranks per clump.
  // sums[2]: the squared evaluated forces of all free atoms (see the estimate below)
  double sums[3] = {0, 0, 0};
  for (std::size_t k = 0; k < n; ++k)
    if (is_free(k))
      for (int d = 0; d < 3; ++d) sums[2] += strength[k] * strength[k] * grad[3 * k + d] * grad[3 * k + d];
  std::vector<std::size_t> pebbles;
  std::vector<double> pa, pe;    // evaluated and exact forces of the sampled pebbles
  for (std::size_t k = 0; k < sample.size(); ++k) {
    const std::size_t j = sample[k];
    const double s = strength[j];
    double e[3], a[3];
    for (int d = 0; d < 3; ++d) {
      // the evaluated gradient has the pairs inside the clump subtracted: so has the reference
      e[d] = s * (exact[3 * k + d] - (is_free(j) ? 0.0 : body_pairs[(std::size_t) KIFMMRigidBodies::nvalues * j + d]));
      a[d] = s * grad[3 * j + d];
    }
    if (is_free(j)) {
      for (int d = 0; d < 3; ++d) {
        sums[0] += (a[d] - e[d]) * (a[d] - e[d]);
        sums[1] += e[d] * e[d];
      }
      continue;
    }
    pebbles.push_back(j);
    pa.insert(pa.end(), a, a + 3);
    pe.insert(pe.end(), e, e + 3);
  }

  double tot[3];
  bigint nfree = (bigint) (sample.size() - pebbles.size()), nfree_all = 0;
  MPI_Allreduce(sums, tot, 3, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(&nfree, &nfree_all, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  MeasuredError m = clump_error(pebbles, pa, pe);
  m.natoms = nfree_all;
  // free atoms: the sample's squared error scaled to all of them over all their squared forces
  if (nfree_all > 0)
    m.atoms = kifmm::sampled_relative_error(tot[0], tot[1], (double) nfree_all, all[0], tot[2]);
  return m;
}

// The relative RMS errors of the clumps' net forces and torques (about their centres of mass),
// forces a against references e at pebbles of clumps (3 values per pebble; every rank its own,
// summed per clump over ranks; collective). Only the clump fields of the result are set.
KSpaceKIFMM::MeasuredError KSpaceKIFMM::clump_error(const std::vector<std::size_t> &pebbles,
                                                     const std::vector<double> &a, const std::vector<double> &e)
{
  std::map<tagint, std::array<double, 12>> clump;    // dF, F, dtau, tau
  for (std::size_t k = 0; k < pebbles.size(); ++k) {
    auto &c = clump.try_emplace(point_body[pebbles[k]]).first->second;
    const double *r = &point_arm[3 * pebbles[k]], *ek = &e[3 * k];
    const double df[3] = {a[3 * k] - ek[0], a[3 * k + 1] - ek[1], a[3 * k + 2] - ek[2]};
    for (int d = 0; d < 3; ++d) {
      c[d] += df[d];
      c[3 + d] += ek[d];
    }
    const double dt[3] = {r[1] * df[2] - r[2] * df[1], r[2] * df[0] - r[0] * df[2], r[0] * df[1] - r[1] * df[0]};
    const double t[3] = {r[1] * ek[2] - r[2] * ek[1], r[2] * ek[0] - r[0] * ek[2], r[0] * ek[1] - r[1] * ek[0]};
    for (int d = 0; d < 3; ++d) {
      c[6 + d] += dt[d];
      c[9 + d] += t[d];
    }
  }
  // each clump's sums go to one rank (its tag modulo the ranks), which adds them up: a rank
  // holds its own clumps and its share of all, not every clump
  const int nranks = kcomm->size();
  std::vector<std::vector<double>> send(nranks), recv;
  for (const auto &[tag, c] : clump) {
    std::vector<double> &to = send[(std::size_t) (tag % nranks)];
    to.push_back((double) tag);
    to.insert(to.end(), c.begin(), c.end());
  }
  kcomm->alltoallv(send, recv);
  std::map<tagint, std::array<double, 12>> whole;
  for (const std::vector<double> &from : recv)
    for (std::size_t k = 0; k + 13 <= from.size(); k += 13) {
      auto &c = whole.try_emplace((tagint) from[k]).first->second;
      for (int m = 0; m < 12; ++m) c[m] += from[k + 1 + m];
    }
  double csum[5] = {0, 0, 0, 0, (double) whole.size()};
  for (const auto &[tag, c] : whole)
    for (int d = 0; d < 3; ++d) {
      csum[0] += c[d] * c[d];
      csum[1] += c[3 + d] * c[3 + d];
      csum[2] += c[6 + d] * c[6 + d];
      csum[3] += c[9 + d] * c[9 + d];
    }
  kcomm->allreduce_sum(csum, 5);
  MeasuredError m;
  m.nclumps = (bigint) csum[4];
  if (m.nclumps > 0) {
    m.clump_force = kifmm::relative_rms(csum[0], csum[1]);
    // clumps of one point (or all pebbles at the centre of mass) have no torque
    if (csum[3] > 0 || csum[2] > 0) m.clump_torque = kifmm::relative_rms(csum[2], csum[3]);
  }
  return m;
}

// The current evaluation against another of the same points (gradients g and, with dipoles,
// Hessians h), over all points: the forces of free atoms (with dipoles: of every point, and
// their torques) and the net forces and torques of clumps, relative to the current values
// (collective). Of two orders, the lower one's error is at most this plus the higher one's.
KSpaceKIFMM::MeasuredError KSpaceKIFMM::difference_from(const std::vector<double> &g, const std::vector<double> &h)
{
  const std::size_t n = index.size();
  const bool with_bodies = !dipoles && !point_body.empty();
  double sums[4] = {0, 0, 0, 0}, tot[4];    // force: difference^2, value^2; torque the same
  bigint nfree = 0, nfree_all = 0;
  std::vector<std::size_t> pebbles;
  std::vector<double> pa, pb;
  for (std::size_t k = 0; k < n; ++k) {
    double fa[3], ta[3], fb[3], tb[3];
    point_force(k, 1.0, fa, ta);
    point_force(k, 1.0, &g[3 * k], dipoles ? &h[6 * k] : nullptr, fb, tb);
    if (with_bodies && point_body[k]) {
      pebbles.push_back(k);
      pa.insert(pa.end(), fa, fa + 3);
      pb.insert(pb.end(), fb, fb + 3);
      continue;
    }
    ++nfree;
    for (int d = 0; d < 3; ++d) {
      sums[0] += (fa[d] - fb[d]) * (fa[d] - fb[d]);
      sums[1] += fa[d] * fa[d];
      sums[2] += (ta[d] - tb[d]) * (ta[d] - tb[d]);
      sums[3] += ta[d] * ta[d];
    }
  }
  MPI_Allreduce(sums, tot, 4, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(&nfree, &nfree_all, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  MeasuredError m = dipoles ? MeasuredError{} : clump_error(pebbles, pa, pb);
  m.natoms = nfree_all;
  if (nfree_all > 0) m.atoms = kifmm::relative_rms(tot[0], tot[1]);
  if (dipoles && (tot[3] > 0 || tot[2] > 0)) m.torques = kifmm::relative_rms(tot[2], tot[3]);
  return m;
}

// The exact gradients at the sample (kifmm::exact_gradient; collective), or those of the last
// measurement when it was of the same step, sample, atoms and kind of reference on every rank.
void KSpaceKIFMM::exact_gradient_at(const std::vector<std::size_t> &sample, std::vector<double> &exact)
{
  unsigned long long h = 1469598103934665603ULL;    // FNV-1a over the words of the points
  auto mix = [&h](const std::vector<double> &v) {
    for (double x : v) {
      unsigned long long w;
      std::memcpy(&w, &x, sizeof w);
      h = (h ^ w) * 1099511628211ULL;
    }
  };
  mix(xyz);
  mix(strength);
  ExactReference &r = exact_reference;
  const int order = kifmm::reference_order(engine->options(), strength.size(), sample.size());
  int same = r.step == update->ntimestep && r.order == order && r.atoms == h && r.sample == sample, all_same = 0;
  MPI_Allreduce(&same, &all_same, 1, MPI_INT, MPI_MIN, world);
  if (all_same) {
    exact = r.exact;
    return;
  }
  std::vector<double> txyz(3 * sample.size());
  exact.assign(3 * sample.size(), 0.0);
  for (std::size_t k = 0; k < sample.size(); ++k)
    for (int d = 0; d < 3; ++d) txyz[3 * k + d] = xyz[3 * sample[k] + d];
  kifmm::exact_gradient(*engine, distributed() ? kcomm.get() : nullptr, strength.size(), xyz.data(),
                        strength.data(), sample.size(), txyz.data(), exact.data());
  r.step = update->ntimestep;
  r.order = order;
  r.atoms = h;
  r.sample = sample;
  r.exact = exact;
  ++r.sums;
}

std::string KSpaceKIFMM::MeasuredError::describe() const
{
  std::string s;
  if (natoms > 0) s += fmt::format("forces of {} atoms {:.3e}", natoms, atoms);
  if (natoms > 0 && torques >= 0) s += fmt::format(", torques {:.3e}", torques);
  if (nclumps > 0) {
    if (!s.empty()) s += "; ";
    s += fmt::format("net forces of {} clumps {:.3e}", nclumps, clump_force);
    if (clump_torque >= 0) s += fmt::format(", torques {:.3e}", clump_torque);
  }
  return s.empty() ? "no atoms" : s;
}

void KSpaceKIFMM::check_error()
{
  const MeasuredError m = measure_error(kset.check_samples);
  last_measured_error = std::max(0.0, m.worst());
  int ivar = input->variable->find(error_variable);
  if (ivar >= 0) input->variable->internal_set(ivar, last_measured_error);
  if (comm->me == 0)
    utils::logmesg(lmp, "KIFMM check at step {}: measured relative force error {:.3e} ({})\n",
                   update->ntimestep, last_measured_error, m.describe());
}

// First evaluation of a run whose order comes from the requested accuracy: the error measured
// on these atoms (free atoms' forces, clumps' net forces and torques), kifmm::search_order. While
// it exceeds the target (3/4 of the request: the sampled error is an estimate), the next order
// is evaluated; while it is below half the target, the order below is tried. Of two orders the
// lower one's error is bounded by their difference over all atoms (difference_from: forces,
// torques of dipoles, clumps' net forces and torques) plus the higher one's sampled error,
// compared with the request itself (when that bound misses and the difference minus the higher
// order's error does not, again from the order above it). Each order is evaluated on the
// tree chosen for it. The order settled on is where the next run of these settings starts.
// Above the calibrated orders a warning gives the error that can be reached.
void KSpaceKIFMM::verify_accuracy(bool want_potential, double &comm_time, std::size_t &nsrc)
{
  verify_pending = false;
  bigint ntotal = 0, nmine = (bigint) index.size();
  MPI_Allreduce(&nmine, &ntotal, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (ntotal < 2) return;
  const int nsamples = kset.check_samples > 0 ? kset.check_samples : verify_samples;
  const int first_order = engine_options.order;
  const kifmm::KernelSpec kernel = engine->kernel();
  // the evaluations of the search (kifmm::search_order): another order on the tree chosen for
  // it, measured on these atoms; each step is logged
  struct Trials : kifmm::OrderTrials {
    KSpaceKIFMM &ks;
    const kifmm::KernelSpec kernel;
    bool want_potential;
    double &comm_time;
    std::size_t &nsrc;
    int nsamples;
    double target;
    MeasuredError m;
    Step why = Step::raise;
    struct Kept {
      std::unique_ptr<kifmm::Evaluator> engine;
      kifmm::Options options;
      std::vector<double> grad, pot, hess;
      MeasuredError m;
    } kept;
    Trials(KSpaceKIFMM &k, bool wp, double &ct, std::size_t &ns, int nsam, double t) :
        ks(k), kernel(k.engine->kernel()), want_potential(wp), comm_time(ct), nsrc(ns), nsamples(nsam), target(t),
        m(k.measure_error(nsam))
    {
    }
    double measure(int order) override
    {
      const int from = ks.engine_options.order;
      const double was = m.worst();
      kifmm::Options opt = ks.engine ? ks.engine->options() : kept.options;
      opt.order = order;
      // the tree for that order (leaf not given; one rank: from the atoms, several: the uniform
      // choice, as the next run of these settings starts with)
      if (ks.kset.leaf <= 0) opt = kifmm::plan_tree(opt, ks.tree_request).options;
      ks.engine = kifmm::make_evaluator(kernel, opt);
      ks.engine_options = ks.engine->options();
      ks.reported_first_evaluation = false;
      if (ks.kset.leaf <= 0 && !ks.distributed()) ks.choose_tree_from_atoms();
      ks.evaluate_points(want_potential, comm_time, nsrc);
      m = ks.measure_error(nsamples);
      if (ks.comm->me != 0) return m.worst();
      if (why == Step::raise)
        utils::logmesg(ks.lmp,
                       "  KIFMM order {} measured {:.3e} on these atoms > {:.3g} (3/4 of the request): "
                       "order {} measured {:.3e} ({})\n",
                       from, was, target, order, m.worst(), m.describe());
      else if (why == Step::lower)
        utils::logmesg(ks.lmp,
                       "  KIFMM order {} measured {:.3e} on these atoms <= {:.3g} (half the target): "
                       "order {} measured {:.3e}\n",
                       from, was, 0.5 * target, order, m.worst());
      else if (why == Step::bound)
        utils::logmesg(ks.lmp, "  KIFMM order {} evaluated to bound the error of order {}: measured {:.3e}\n", order,
                       from, m.worst());
      else
        utils::logmesg(ks.lmp, "  KIFMM back to order {}: measured {:.3e}\n", order, m.worst());
      return m.worst();
    }
    void step(Step s) override { why = s; }
    void keep() override
    {
      kept.options = ks.engine->options();
      kept.engine = std::move(ks.engine);
      kept.grad = ks.grad;
      kept.pot = ks.pot;
      kept.hess = ks.hess;
      kept.m = m;
    }
    // the two evaluations' difference over all atoms, measured as the error is (forces of free
    // atoms, torques of dipoles, net forces and torques of clumps)
    double difference_from_kept() override
    {
      const MeasuredError d = ks.difference_from(kept.grad, kept.hess);
      if (ks.comm->me == 0)
        utils::logmesg(ks.lmp, "  KIFMM orders {} and {} differ by {:.3e} over all atoms ({})\n", kept.options.order,
                       ks.engine_options.order, d.worst(), d.describe());
      return d.worst();
    }
    void restore() override
    {
      ks.engine = std::move(kept.engine);
      ks.engine_options = kept.options;
      ks.grad = kept.grad;
      ks.pot = kept.pot;
      ks.hess = kept.hess;
      m = kept.m;
    }
  } trials(*this, want_potential, comm_time, nsrc, nsamples, verify_margin * kset.accuracy);
  const int max_order = kifmm::max_calibrated_order();
  const kifmm::OrderFound found = kifmm::search_order(trials, kifmm::OrderFound{first_order, trials.m.worst()},
                                                      kset.accuracy, min_tried_order, max_order);
  const MeasuredError &m = trials.m;
  // the error of the order settled on: the sampled one, or the bound from the difference to
  // the next order over all atoms when that decided
  verified_error = found.order == engine_options.order && found.error >= 0 ? found.error : m.worst();
  chosen_order = engine_options.order;
  if (comm->me == 0) {
    const kifmm::Options &o = engine_options;
    const std::string tree = o.periodic_grid > 0
        ? fmt::format("periodic single-level grid of {} cells", grid_cells_text(o))
        : fmt::format("leaf size {}, tree depth {}", o.leaf_size, engine->stats().depth);
    if (verified_error > kset.accuracy)
      error->warning(FLERR,
                     "kspace_style kifmm: the requested accuracy {:.3g} is out of reach for these "
                     "atoms: measured {:.3e} at order {}, the highest calibrated order ({})",
                     kset.accuracy, verified_error, engine_options.order, m.describe());
    else if (verified_error != m.worst())
      utils::logmesg(lmp,
                     "  KIFMM order {} on {}: relative error at most {:.3e} (its difference to a higher order "
                     "over all atoms plus that order's sampled error; sampled at order {}: {}), requested {:.3g}\n",
                     engine_options.order, tree, verified_error, engine_options.order, m.describe(), kset.accuracy);
    else
      utils::logmesg(lmp, "  KIFMM order {} on {}: measured relative error {:.3e} ({}), requested {:.3g}\n",
                     engine_options.order, tree, m.worst(), m.describe(), kset.accuracy);
  }
}
