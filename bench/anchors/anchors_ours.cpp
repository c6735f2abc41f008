// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Our engine on the anchor benchmark's problem (anchors_problem.h). A setting is a requested
// accuracy, ACC (order and tree chosen by the engine, as kspace_style kifmm does without a leaf
// size: kifmm::choose_order, then kifmm::plan_tree and the choice from the points,
// kifmm::choose_tree_from_points) or ACC:LEAF (order chosen for ACC, leaf size given).
// Timed: Evaluator::evaluate (tree, lists, all passes; potential and gradient of all points),
// after W untimed evaluations (--warmup; an evaluation that built operators is never timed).
// Not timed, reported: the tree choice from the points (choice=, seconds) and the operator
// precomputation (precompute=).
// Usage: anchors_ours PROBLEM_FILE --settings ACC[:LEAF],... [--reps R] [--warmup W]
#include "anchors_problem.h"
#include "kifmm.h"

int main(int argc, char **argv)
{
  const anchors::Args a = anchors::parse_args(argc, argv, "PROBLEM_FILE --settings ACC[:LEAF],... [--reps R] [--warmup W]");
  const anchors::Problem p = anchors::read_problem(a.file);
  const kifmm::KernelSpec kernel{};
  std::vector<double> pot(p.n), grad(3 * p.n);
  for (const auto &s : a.settings) {
    const double acc = s.first;
    const int leaf = (int) s.second;
    kifmm::Options opt;
    opt.order = kifmm::choose_order(kernel, acc).order;
    const kifmm::TreeRequest request{p.n, leaf, 0, false};
    const kifmm::TreePlan plan = kifmm::plan_tree(opt, request);
    opt = plan.options;
    const anchors::Clock c0 = anchors::Clock::now();
    if (plan.from_points) kifmm::choose_tree_from_points(kernel, request, opt, p.n, p.xyz.data());
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
      char extra[160];
      std::snprintf(extra, sizeof(extra), "choice=%.3f precompute=%.3f precompute_in_timed=%.3f", t_choice, t_pre,
                    ev->stats().t_precompute);
      anchors::print_row("ours", p, setting, opt.order, opt.leaf_size, ev->stats().depth, err, t, extra);
    }
  }
  return 0;
}
