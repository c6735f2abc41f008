// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// What a caller of the engine needs besides the potentials and gradients: the memory an
// evaluation will take, the per-point virial, and the exact reference of the sampled error
// check (kifmm.h).
#include "communicator.h"
#include "kifmm.h"
#include "periodic.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace kifmm {

double estimate_memory_bytes(const Options &opt, std::size_t n_sources, std::size_t operator_bytes)
{
  const double p = opt.order, m = std::max(1, opt.leaf_size);
  const double leaves = std::max(1.0, (double) n_sources / (0.5 * m));
  // per point: coordinates, strength, sort keys, gradients, potential, target copies (~30
  // doubles); per cell: up/down equivalent densities and check values, the FFT of the
  // upward density and the M2L accumulation ((2p)^3 complex each); operators as reported
  const double surface = 6.0 * (p - 1) * (p - 1) + 2.0, grid = 8.0 * p * p * p;
  double bytes = 30.0 * 8.0 * (double) n_sources +
      leaves * 8.0 / 7.0 * (4.0 * surface * 8.0 + 2.0 * grid * 16.0) + (double) operator_bytes;
  // periodic single-level grid: the spectra of all cells ((2p)^2 (p+1) complex each)
  const double kg = opt.periodic_grid;
  bytes += kg * kg * kg * (4.0 * p * p * (p + 1) * 16.0 + 4.0 * surface * 8.0);
  return bytes;
}

void point_virial(Evaluator &ev, Communicator *comm, std::size_t n, const double *xyz,
                  const double *q, const double *grad, double prefactor, double *virial,
                  double center[3])
{
  // centre of the points' bounding box (all ranks), to limit cancellation
  double box[6] = {1e300, 1e300, 1e300, 1e300, 1e300, 1e300};    // lo, -hi
  for (std::size_t k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d) {
      box[d] = std::min(box[d], xyz[3 * k + d]);
      box[3 + d] = std::min(box[3 + d], -xyz[3 * k + d]);
    }
  if (comm) comm->allreduce_min(box, 6);
  for (int d = 0; d < 3; ++d) center[d] = 0.5 * (box[d] - box[3 + d]);

  std::fill(virial, virial + 6 * n, 0.0);
  std::vector<double> moment(n), g(3 * n);
  // component (a, b), a <= b, in the order xx yy zz xy xz yz
  const int slot[3][3] = {{0, 3, 4}, {-1, 1, 5}, {-1, -1, 2}};
  for (int a = 0; a < 3; ++a) {
    for (std::size_t j = 0; j < n; ++j) moment[j] = q[j] * (xyz[3 * j + a] - center[a]);
    std::fill(g.begin(), g.end(), 0.0);
    if (comm && comm->size() > 1)
      ev.evaluate_distributed(*comm, n, xyz, moment.data(), nullptr, g.data());
    else if (n > 0)
      ev.evaluate(n, xyz, moment.data(), n, xyz, nullptr, g.data());
    for (std::size_t k = 0; k < n; ++k) {
      const double s = q[k], xa = xyz[3 * k + a] - center[a];
      for (int b = a; b < 3; ++b)
        virial[6 * k + slot[a][b]] =
            0.5 * (xa * prefactor * s * grad[3 * k + b] - prefactor * s * g[3 * k + b]);
    }
  }
}

namespace {

// Collective: the targets of all ranks on every rank (few); sum(m, xyz, out) puts this rank's
// sources' values at m targets into out (width values per target, laid out as the caller's sum
// does), and the values are added over the ranks (the references are linear in the sources).
// Returns the values of all targets; first: the index of this rank's first target.
template <class Sum>
std::vector<double> summed_at_all_targets(Communicator &comm, std::size_t n_trg, const double *trg_xyz,
                                          std::size_t width, const Sum &sum, std::size_t &first)
{
  std::vector<double> mine(trg_xyz, trg_xyz + 3 * n_trg), all;
  std::vector<int> counts;
  comm.allgatherv(mine, all, counts);
  first = 0;
  for (int r = 0; r < comm.rank(); ++r) first += (std::size_t) counts[r] / 3;
  const std::size_t m = all.size() / 3;
  std::vector<double> out(width * m, 0.0);
  sum(m, all.data(), out.data());
  if (!out.empty()) comm.allreduce_sum(out.data(), out.size());
  return out;
}

// The Ewald sum of periodic_direct_sum costs about 0.35 us per source-target pair on one core
// (erfc terms of about 6 images per pair; 35 s for 1000 targets of 1e5 sources), the engine at
// order 14 about 6 us per source (0.6 s at 1e5; its operators once per process, or once per
// operator cache). It agrees with the Ewald sum to 1e-11 .. 4e-11 (calibration.cpp), 17 times or
// more below the error of order 11 and below, which it serves.
constexpr double kEwaldPairs = 5e6;
constexpr int kEngineReferenceOrder = 14, kEngineReferenceAbove = 11;

// the engine at order 14 on the tree of choose_tree for the cell (an octree or a grid; in cells
// the octree does not fit a grid): 1e-11 on the tests' boxes up to 1:2, charges; 4e-12 with
// dipoles (gradients and second derivatives)
Options reference_options(const Options &opt, std::size_t n_src)
{
  Options hi = opt;
  hi.order = kEngineReferenceOrder;
  const TreeChoice c = choose_tree(hi.order, n_src, true, true, opt.root_shape);
  hi.leaf_size = c.leaf_size;
  hi.periodic_grid = c.grid;
  return hi;
}
}    // namespace

int reference_order(const Options &opt, std::size_t n_src, std::size_t n_trg)
{
  if (!opt.periodic || opt.periodic_dims == 2 || opt.order > kEngineReferenceAbove) return 0;
  if ((double) n_src * (double) n_trg <= kEwaldPairs) return 0;
  const bool fits = octree_fits_cell(opt.root_shape) || reference_options(opt, n_src).periodic_grid > 0;
  return fits ? kEngineReferenceOrder : 0;
}

void exact_gradient(const Evaluator &ev, Communicator *comm, std::size_t n_src,
                    const double *src_xyz, const double *src_q, std::size_t n_trg,
                    const double *trg_xyz, double *grad)
{
  const Options &opt = ev.options();
  auto sum = [&](std::size_t nt, const double *t, double *g) {
    if (nt == 0 || n_src == 0) return;
    if (reference_order(opt, n_src, nt) > 0) {    // a large periodic box
      make_evaluator(ev.kernel(), reference_options(opt, n_src))->evaluate(n_src, src_xyz, src_q, nt, t, nullptr, g);
      return;
    }
    // slabs: the exact doubly periodic sum costs O(N M K): the 3-d route above a few 1e5 pairs
    if (opt.periodic && opt.periodic_dims == 2 && (double) n_src * nt <= 2e5)
      slab_direct_sum(opt.root_center, opt.root_half_width, opt.root_shape, n_src, src_xyz, src_q, nt, t, nullptr, g);
    else if (opt.periodic && opt.periodic_dims == 2)
      slab_gradient_via_3d(opt.root_center, opt.root_half_width, opt.root_shape, n_src, src_xyz, src_q, nt, t, g);
    else if (opt.periodic)
      periodic_direct_sum(ev.kernel(), opt.root_center, opt.root_half_width, n_src, src_xyz, src_q,
                          nt, t, nullptr, g, opt.root_shape);
    else
      direct_sum(ev.kernel(), n_src, src_xyz, src_q, nt, t, nullptr, g);
  };
  if (!comm || comm->size() == 1) {
    sum(n_trg, trg_xyz, grad);
    return;
  }
  std::size_t first = 0;
  const std::vector<double> g = summed_at_all_targets(*comm, n_trg, trg_xyz, 3, sum, first);
  std::copy(g.begin() + 3 * first, g.begin() + 3 * (first + n_trg), grad);
}

void exact_dipole_field(const Evaluator &ev, Communicator *comm, std::size_t n_src, const double *src_xyz,
                        const double *src_q, const double *src_mu, std::size_t n_trg, const double *trg_xyz,
                        double *grad, double *hess)
{
  const Options &opt = ev.options();
  auto sum = [&](std::size_t nt, const double *t, double *g, double *h) {
    if (nt == 0 || n_src == 0) return;
    if (opt.periodic && (opt.periodic_dims == 2 || ev.kernel().type != KernelType::Laplace)) {
      // a slab, periodic yukawa: the engine itself at order 14
      Options hi = opt;
      hi.order = 14;
      hi.leaf_size = 0;
      hi.cache_dir.clear();
      make_evaluator(ev.kernel(), hi)->evaluate_dipoles(n_src, src_xyz, src_q, src_mu, nt, t, nullptr, g, h);
    } else if (opt.periodic && reference_order(opt, n_src, nt) > 0)    // a large p p p box (as exact_gradient)
      make_evaluator(ev.kernel(), reference_options(opt, n_src))
          ->evaluate_dipoles(n_src, src_xyz, src_q, src_mu, nt, t, nullptr, g, h);
    else if (opt.periodic)
      periodic_dipole_direct_sum(opt.root_center, opt.root_half_width, opt.root_shape, n_src, src_xyz, src_q, src_mu,
                                 nt, t, nullptr, g, h);
    else
      direct_sum_dipoles(ev.kernel(), n_src, src_xyz, src_q, src_mu, nt, t, nullptr, g, h);
  };
  if (!comm || comm->size() == 1) {
    std::fill(grad, grad + 3 * n_trg, 0.0);
    if (hess) std::fill(hess, hess + 6 * n_trg, 0.0);
    sum(n_trg, trg_xyz, grad, hess);
    return;
  }
  // (the gradients of all targets, then their second derivatives)
  auto both = [&](std::size_t m, const double *t, double *out) { sum(m, t, out, out + 3 * m); };
  std::size_t first = 0;
  const std::vector<double> gh = summed_at_all_targets(*comm, n_trg, trg_xyz, 9, both, first);
  const std::size_t m = gh.size() / 9;
  std::copy(gh.begin() + 3 * first, gh.begin() + 3 * (first + n_trg), grad);
  if (hess) std::copy(gh.begin() + 3 * m + 6 * first, gh.begin() + 3 * m + 6 * (first + n_trg), hess);
}

std::vector<std::size_t> sample_without_replacement(std::vector<std::size_t> candidates,
                                                    std::size_t want, unsigned long long seed)
{
  if (want >= candidates.size()) return candidates;
  std::mt19937_64 rng(seed);
  std::vector<std::size_t> sample;
  for (std::size_t k = 0; k < want; ++k) {    // partial Fisher-Yates shuffle
    std::uniform_int_distribution<std::size_t> pick(k, candidates.size() - 1);
    std::swap(candidates[k], candidates[pick(rng)]);
    sample.push_back(candidates[k]);
  }
  return sample;
}

double relative_rms(double diff2, double ref2)
{
  return ref2 > 0 ? std::sqrt(diff2 / ref2) : (diff2 > 0 ? INFINITY : 0.0);
}

double sampled_relative_error(double sample_diff2, double sample_ref2, double n_sampled,
                              double n_all, double all_evaluated2)
{
  if (n_sampled <= 0) return -1.0;
  if (n_sampled >= n_all) return relative_rms(sample_diff2, sample_ref2);
  return relative_rms(sample_diff2 * n_all / n_sampled, all_evaluated2);
}

}    // namespace kifmm
