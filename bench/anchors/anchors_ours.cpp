// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Our engine on the anchor benchmark's problem (anchors_problem.h). A setting is a requested
// accuracy, ACC (order and tree chosen by the engine, as kspace_style kifmm does on one rank
// without a leaf size: kifmm::choose_order, then kifmm::plan_tree and the choice from the
// points, kifmm::choose_tree_from_points, then the order measured on the points,
// kifmm::search_order, with 1000 sampled targets other than the benchmark's error targets;
// then the tree tuned by timing the trees near it, kifmm::TreeTuner, a tree whose error on those
// targets misses the request not used; bench/measured_order.h) or ACC:LEAF (order of the
// calibration table for ACC, leaf size given).
// Timed: Evaluator::evaluate (tree, lists, all passes; potential and gradient of all points),
// after W untimed evaluations (--warmup; an evaluation that built operators is never timed).
// Not timed, reported: the tree choice, the order search and the tuning (choice=, seconds, with
// the search's evaluations, search_evaluations=, and the tuning's, tune_evaluations=) and the
// operator precomputation (precompute=).
// Usage: anchors_ours PROBLEM_FILE --settings ACC[:LEAF],... [--reps R] [--warmup W]
#include "anchors_problem.h"
#include "kifmm.h"
#include "../measured_order.h"

#include <algorithm>
#include <numeric>

int main(int argc, char **argv)
{
  const anchors::Args a = anchors::parse_args(argc, argv, "PROBLEM_FILE --settings ACC[:LEAF],... [--reps R] [--warmup W]");
  const anchors::Problem p = anchors::read_problem(a.file);
  const kifmm::KernelSpec kernel{};
  std::vector<double> pot(p.n), grad(3 * p.n);
  // the order search's targets: sampled among the points that are not error targets
  std::vector<std::size_t> others(p.n), search;
  std::iota(others.begin(), others.end(), 0);
  for (std::uint64_t i : p.sample) others[i] = p.n;
  others.erase(std::remove(others.begin(), others.end(), (std::size_t) p.n), others.end());
  search = kifmm::sample_without_replacement(others, kifmm::order_search_samples, 7654321ULL);
  std::vector<double> search_xyz(3 * search.size()), search_pot(search.size()), search_exact(3 * search.size());
  for (std::size_t k = 0; k < search.size(); ++k)
    for (int d = 0; d < 3; ++d) search_xyz[3 * k + d] = p.xyz[3 * search[k] + d];
  kifmm::direct_sum(kernel, p.n, p.xyz.data(), p.q.data(), search.size(), search_xyz.data(), search_pot.data(),
                    search_exact.data());
  for (const auto &s : a.settings) {
    const double acc = s.first;
    const int leaf = (int) s.second;
    kifmm::Options opt;
    int search_evaluations = 0, tune_evaluations = 0;
    const anchors::Clock c0 = anchors::Clock::now();
    if (leaf > 0) {
      opt.order = kifmm::choose_order(kernel, acc).order;
      opt = kifmm::plan_tree(opt, kifmm::TreeRequest{p.n, leaf, 0, false}).options;
    } else {
      const bench::MeasuredOrder m =
          bench::measured_order(kernel, kifmm::Options{}, acc, p.n, p.xyz.data(), p.q.data(), search, search_exact);
      search_evaluations = m.evaluations;
      // the tree tuned at that order, as kspace_style kifmm tunes it (CPU time on one thread,
      // wall time on more)
      const bool cpu = anchors::compare_cpu();
      opt = bench::tuned_options(
          kernel, m, acc, p.n, p.xyz.data(), p.q.data(), search, search_exact,
          [cpu]() { const anchors::Clock t = anchors::Clock::now(); return cpu ? t.cpu : t.wall; },
          tune_evaluations);
    }
    const double t_choice = (anchors::Clock::now() - c0).wall;
    auto ev = kifmm::make_evaluator(kernel, opt);
    double t_pre = 0;
    char setting[64];
    std::snprintf(setting, sizeof(setting), leaf > 0 ? "acc%g:leaf%d" : "acc%g", acc, leaf);
    for (int r = -a.warmup; r < a.reps; ++r) {
      anchors::Clock t{0, 0};
      // an evaluation that built operators (the first of this order, also without warm-up) is
      // repeated: the operator precomputation is not timed
      do {
        const anchors::Clock t0 = anchors::Clock::now();
        ev->evaluate(p.n, p.xyz.data(), p.q.data(), p.n, p.xyz.data(), pot.data(), grad.data());
        t = anchors::Clock::now() - t0;
        t_pre += ev->stats().t_precompute;
      } while (ev->stats().t_precompute > 0);
      if (r < 0) continue;
      const double err = anchors::gradient_error(p, grad.data(), 1.0);
      char extra[240];
      std::snprintf(extra, sizeof(extra),
                    "choice=%.3f search_evaluations=%d tune_evaluations=%d precompute=%.3f precompute_in_timed=%.3f",
                    t_choice, search_evaluations, tune_evaluations, t_pre, ev->stats().t_precompute);
      anchors::print_row("ours", p, setting, opt.order, opt.leaf_size, ev->stats().depth, err, t, extra);
    }
  }
  return 0;
}
