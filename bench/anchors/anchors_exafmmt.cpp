// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// exafmm-t on the anchor benchmark's problem (anchors_problem.h), double precision. A setting is
// P:NCRIT (expansion order p; max bodies per leaf). Potential and gradient of all points
// (LaplaceFmm, sources = targets as two body arrays, as its examples do).
// Timed: get_bounds + build_tree + build_list (tree, lists) + M2L_setup + upward_pass +
// downward_pass, after one untimed cycle. Not timed: init_rel_coord (tables of relative
// positions, once per process), precompute (operators; saved to and read from --cache DIR when
// given), copying the points into its bodies and the results out of its leaves.
// Usage: anchors_exafmmt PROBLEM_FILE --settings P:NCRIT,... [--reps R] [--warmup W] [--cache DIR]
#include "anchors_problem.h"

#include "build_list.h"
#include "build_tree.h"
#include "laplace.h"

int main(int argc, char **argv)
{
  using namespace exafmm_t;
  const anchors::Args a = anchors::parse_args(argc, argv, "PROBLEM_FILE --settings P:NCRIT,... [--reps R] [--warmup W] [--cache DIR]");
  const anchors::Problem p = anchors::read_problem(a.file);
  std::vector<double> grad(3 * p.n);
  init_rel_coord();
  std::string tag = a.file.substr(a.file.find_last_of('/') + 1);
  for (const auto &s : a.settings) {
    const int order = (int) s.first, ncrit = (int) s.second;
    const std::string cache =
        a.cache.empty() ? std::string() : a.cache + "/exafmmt_laplace_p" + std::to_string(order) + "_" + tag + ".dat";
    char setting[64];
    std::snprintf(setting, sizeof(setting), "p%d:ncrit%d", order, ncrit);
    double t_pre = 0;
    for (int r = -a.warmup; r < a.reps; ++r) {
      Bodies<real_t> sources(p.n), targets(p.n);
      for (std::size_t i = 0; i < p.n; ++i) {
        sources[i].ibody = targets[i].ibody = (int) i;
        sources[i].q = p.q[i];
        for (int d = 0; d < 3; ++d) sources[i].X[d] = targets[i].X[d] = p.xyz[3 * i + d];
      }
      LaplaceFmm fmm(order, ncrit, cache);
      NodePtrs<real_t> leafs, nonleafs;
      const anchors::Clock t0 = anchors::Clock::now();
      get_bounds(sources, targets, fmm.x0, fmm.r0);
      Nodes<real_t> nodes = build_tree(sources, targets, leafs, nonleafs, fmm);
      build_list(nodes, fmm);
      const anchors::Clock t1 = anchors::Clock::now();
      fmm.precompute();
      const anchors::Clock t2 = anchors::Clock::now();
      fmm.M2L_setup(nonleafs);
      fmm.upward_pass(nodes, leafs);
      fmm.downward_pass(nodes, leafs);
      const anchors::Clock t3 = anchors::Clock::now();
      const anchors::Clock t = (t1 - t0) + (t3 - t2);
      t_pre += (t2 - t1).wall;
      if (r < 0) continue;
      for (Node<real_t> *leaf : leafs)
        for (std::size_t j = 0; j < leaf->itrgs.size(); ++j)
          for (int d = 0; d < 3; ++d) grad[3 * leaf->itrgs[j] + d] = leaf->trg_value[4 * j + 1 + d];
      // exafmm-t: 1/(4 pi r) and the gradient
      const double err = anchors::gradient_error(p, grad.data(), 4 * M_PI);
      char extra[96];
      std::snprintf(extra, sizeof(extra), "precompute=%.3f", t_pre);
      anchors::print_row("exafmmt", p, setting, order, ncrit, fmm.depth, err, t, extra);
    }
  }
  return 0;
}
