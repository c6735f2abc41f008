// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The order for a requested accuracy as kspace_style kifmm finds it at the start of a run on one
// rank, for the benchmark programs: the calibrated order (kifmm::choose_order) on the tree
// chosen for it (plan_tree + choose_tree_from_points), then kifmm::search_order with the sampled
// error (kifmm::order_search_samples targets against their exact gradients, the squared error
// scaled to all points over the squared evaluated gradients of all points, wanted at
// kifmm::order_search_margin of the request; of two orders the lower one's error bounded by
// their difference over all points plus the higher one's error), each order on the tree chosen
// for it. Sources = targets = xyz, potential and gradient.
#pragma once

#include "kifmm.h"

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <utility>
#include <vector>

namespace bench {

// The sampled error of gradients grad of all n points (charges q) against the exact gradients
// of the sampled ones, as kspace_style kifmm measures it (kifmm::sampled_relative_error)
inline double sampled_error(std::size_t n, const double *q, const double *grad, const std::vector<std::size_t> &sample,
                            const std::vector<double> &sample_exact)
{
  double d2 = 0, r2 = 0, all2 = 0;
  for (std::size_t k = 0; k < sample.size(); ++k)
    for (int d = 0; d < 3; ++d) {
      const double qi = q[sample[k]], a = qi * grad[3 * sample[k] + d], e = qi * sample_exact[3 * k + d];
      d2 += (a - e) * (a - e);
      r2 += e * e;
    }
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) all2 += q[i] * q[i] * grad[3 * i + d] * grad[3 * i + d];
  return kifmm::sampled_relative_error(d2, r2, (double) sample.size(), (double) n, all2);
}

// An evaluation at an order on a fixed tree, and its sampled error
struct SampledOrderTrials : kifmm::OrderTrials {
  const kifmm::KernelSpec kernel;
  std::size_t n;
  const double *xyz, *q;
  kifmm::Options options;
  std::vector<std::size_t> sample;
  std::vector<double> sample_exact, grad, kept_grad;
  kifmm::Options kept_options;
  int evaluations = 0;
  kifmm::TreeRequest tree;    // the tree of each order: chosen for it from the points
  SampledOrderTrials(const kifmm::KernelSpec &k, std::size_t n_points, const double *points, const double *charges,
                     const kifmm::Options &o, const kifmm::TreeRequest &r, std::vector<std::size_t> s,
                     std::vector<double> exact) :
      kernel(k), n(n_points), xyz(points), q(charges), options(o), sample(std::move(s)),
      sample_exact(std::move(exact)), grad(3 * n_points), tree(r)
  {
  }
  // the options of an order: its tree planned and chosen from the points
  void choose(int order)
  {
    options.order = order;
    options = kifmm::plan_tree(options, tree).options;
    kifmm::choose_tree_from_points(kernel, tree, options, n, xyz);
  }
  double evaluate_and_measure()
  {
    std::vector<double> pot(n);
    kifmm::make_evaluator(kernel, options)->evaluate(n, xyz, q, n, xyz, pot.data(), grad.data());
    ++evaluations;
    return sampled_error(n, q, grad.data(), sample, sample_exact);
  }
  double measure(int order) override
  {
    choose(order);
    const double e = evaluate_and_measure();
    if (std::getenv("KIFMM_BENCH_TRACE"))
      std::fprintf(stderr, "  order %d (leaf %d): sampled %.3e\n", order, options.leaf_size, e);
    return e;
  }
  void keep() override
  {
    kept_options = options;
    kept_grad = grad;
  }
  double difference_from_kept() override
  {
    double d2 = 0, all2 = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) {
        const double a = q[i] * grad[3 * i + d], b = q[i] * kept_grad[3 * i + d];
        d2 += (a - b) * (a - b);
        all2 += a * a;
      }
    const double diff = kifmm::relative_rms(d2, all2);
    if (std::getenv("KIFMM_BENCH_TRACE"))
      std::fprintf(stderr, "  orders %d and %d differ by %.3e\n", kept_options.order, options.order, diff);
    return diff;
  }
  void restore() override
  {
    options = kept_options;
    grad = kept_grad;
  }
};

struct MeasuredOrder {
  int calibrated;           // the order of the calibration table
  kifmm::Options options;   // order and tree chosen
  kifmm::OrderFound found;  // the order and its error estimate (sampled, or the bound)
  std::vector<double> grad; // gradients of all points at the chosen options
  int evaluations;          // evaluations of the search
};

// base: boundary and root (periodic, fixed_root, root_half_width); sample_exact: the exact
// gradients (3 per sampled target, in the order of sample)
inline MeasuredOrder measured_order(const kifmm::KernelSpec &kernel, const kifmm::Options &base, double request,
                                    std::size_t n, const double *xyz, const double *q,
                                    const std::vector<std::size_t> &sample, const std::vector<double> &sample_exact)
{
  const kifmm::TreeRequest tree{n, 0, base.periodic ? -1 : 0, false};
  const int calibrated = kifmm::choose_order(kernel, request, base.periodic).order;
  SampledOrderTrials t(kernel, n, xyz, q, base, tree, sample, sample_exact);
  t.choose(calibrated);
  const double first = t.evaluate_and_measure();
  if (std::getenv("KIFMM_BENCH_TRACE"))
    std::fprintf(stderr, "  order %d (leaf %d): sampled %.3e\n", calibrated, t.options.leaf_size, first);
  const kifmm::OrderFound f =
      kifmm::search_order(t, {calibrated, first}, request, 3, kifmm::max_calibrated_order());
  return MeasuredOrder{calibrated, t.options, f, t.grad, t.evaluations};
}

// The tree kspace_style kifmm keeps after tuning it at the measured order (kifmm::TreeTuner,
// one process, open boundaries, no leaf size given): the trees near the chosen one, each timed
// on real evaluations by seconds() (a clock), the fastest kept; a tree whose sampled error
// exceeds order_search_margin * request after its first evaluation is not used. Returns the
// options of the tree kept; evaluations: the tuning's evaluations.
template <class Clock>
kifmm::Options tuned_options(const kifmm::KernelSpec &kernel, const MeasuredOrder &m, double request, std::size_t n,
                             const double *xyz, const double *q, const std::vector<std::size_t> &sample,
                             const std::vector<double> &sample_exact, Clock seconds, int &evaluations)
{
  const kifmm::TreeRequest tree{n, 0, m.options.periodic ? -1 : 0, false};
  kifmm::TreeTuner tuner(kernel, tree, m.options, n, xyz);
  std::unique_ptr<kifmm::Evaluator> ev = kifmm::make_evaluator(kernel, m.options);
  std::vector<double> pot(n), grad(3 * n);
  while (tuner.tuning()) {
    tuner.select(ev);
    const double t0 = seconds();
    ev->evaluate(n, xyz, q, n, xyz, pot.data(), grad.data());
    const double t = seconds() - t0 - ev->stats().t_precompute;
    if (tuner.new_tree() &&
        sampled_error(n, q, grad.data(), sample, sample_exact) > kifmm::order_search_margin * request)
      tuner.reject(ev);
    else
      tuner.record(t);
  }
  evaluations = tuner.evaluations();
  tuner.finish(ev);
  return ev->options();
}

}    // namespace bench
