// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Cost of a periodic (p p p) evaluation in a rectangular box relative to a cube of the same N
// and order, measured in the same run as CPU time of the process (run with OMP_NUM_THREADS=1),
// minimum of --reps, the two evaluators timed alternately. Both use what kspace_style kifmm
// chooses on one rank from the points (choose_tree(kernel, options, n, xyz): in the cube the
// octree or a single-level grid; in a box that is not nearly cubic a grid of nearly cubic
// cells). Uniform random neutral charges filling each box; potential + gradient, sources =
// targets. The relative RMS gradient error of each, on --sample targets against the Ewald sum
// (periodic_direct_sum), is printed beside.
//   bench_periodic_box [--sizes 1e4,1e5] [--orders 4,6,8] [--boxes 2:1:1,1:1:0.5,...]
//                      [--reps 3] [--sample 200] [--phases] [--box-grid K]
// --phases: a row per evaluator with the time of its passes (upward, M2L, downward, near field).
// --box-grid K: the boxes on the grid with K cells along their longest axis, not the choice.
#include "cost_model.h"
#include "fmm_core.h"
#include "kifmm.h"
#include "periodic.h"

#include "bench_points.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace kifmm;

namespace {

std::vector<std::string> split(const char *s, char sep)
{
  std::vector<std::string> v;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, sep)) v.push_back(tok);
  return v;
}

double cpu_now()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

struct Box {
  std::string name;
  double edge[3];
};

// The evaluator kspace_style kifmm would use for these points in this box (largest edge 2).
// grid > 0: that grid (cells along the longest axis) instead of the choice.
std::unique_ptr<Evaluator> chosen(const bench::Points &p, const Box &b, int order, std::string &what, int grid = 0)
{
  Options o;
  o.order = order;
  o.fixed_root = true;
  o.periodic = true;
  const double m = std::max(b.edge[0], std::max(b.edge[1], b.edge[2]));
  o.root_half_width = 1.0;
  for (int d = 0; d < 3; ++d) o.root_shape[d] = b.edge[d] / m;
  TreeRequest req;
  req.n = p.size();
  req.grid = -1;
  TreePlan plan = plan_tree(o, req);
  o = plan.options;
  choose_tree_from_points(KernelSpec{}, req, o, p.size(), p.xyz.data());
  if (grid > 0) o.periodic_grid = grid;
  if (o.periodic_grid > 0) {
    int c[3];
    grid_cells_per_axis(o.periodic_grid, o.root_shape, c);
    what = "grid " + std::to_string(c[0]) + "x" + std::to_string(c[1]) + "x" + std::to_string(c[2]);
  } else {
    what = "octree leaf " + std::to_string(o.leaf_size);
  }
  return make_evaluator(KernelSpec{}, o);
}

// uniform neutral charges filling the box (largest edge 2, centred at 0)
bench::Points box_points(std::size_t n, const Box &b, unsigned seed)
{
  bench::Points p = bench::uniform(n, seed);
  const double m = std::max(b.edge[0], std::max(b.edge[1], b.edge[2]));
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] *= b.edge[d] / m;
  double s = 0;
  for (double q : p.q) s += q;
  for (double &q : p.q) q -= s / n;
  return p;
}

double sampled_error(const Evaluator &ev, const bench::Points &p, const std::vector<double> &g, int sample)
{
  const std::size_t n = p.size(), ns = std::min<std::size_t>(sample, n);
  std::vector<double> tx(3 * ns), rg(3 * ns);
  for (std::size_t k = 0; k < ns; ++k)
    for (int d = 0; d < 3; ++d) tx[3 * k + d] = p.xyz[3 * (k * n / ns) + d];
  const Options &o = ev.options();
  periodic_direct_sum(KernelSpec{}, o.root_center, o.root_half_width, n, p.xyz.data(), p.q.data(), ns, tx.data(),
                      nullptr, rg.data(), o.root_shape);
  double e2 = 0, r2 = 0;
  for (std::size_t k = 0; k < ns; ++k)
    for (int d = 0; d < 3; ++d) {
      const double a = g[3 * (k * n / ns) + d], b = rg[3 * k + d];
      e2 += (a - b) * (a - b);
      r2 += b * b;
    }
  return std::sqrt(e2 / r2);
}

}    // namespace

int main(int argc, char **argv)
{
  std::vector<std::string> sizes{"1e4", "1e5"}, orders{"4", "6", "8"},
      boxes{"1.3:1:1", "2:1:1", "1:1:0.5", "4:1:1", "8:1:1"};
  int reps = 3, sample = 200;
  bool phases = false;
  int box_grid = 0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--sizes") && i + 1 < argc) sizes = split(argv[++i], ',');
    else if (!std::strcmp(argv[i], "--orders") && i + 1 < argc) orders = split(argv[++i], ',');
    else if (!std::strcmp(argv[i], "--boxes") && i + 1 < argc) boxes = split(argv[++i], ',');
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--sample") && i + 1 < argc) sample = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--phases")) phases = true;
    else if (!std::strcmp(argv[i], "--box-grid") && i + 1 < argc) box_grid = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--sizes ..] [--orders ..] [--boxes a:b:c,..] [--reps R] [--sample S] [--phases] "
                   "[--box-grid K]\n",
                   argv[0]);
      return 2;
    }
  }
  std::printf("| N | order | box | box: choice | cube: choice | box / cube CPU time | box s | cube s | "
              "box error | cube error |\n|---|---|---|---|---|---|---|---|---|---|\n");
  const Box cube{"1:1:1", {1, 1, 1}};
  for (const std::string &ns : sizes) {
    const std::size_t n = (std::size_t) std::atof(ns.c_str());
    for (const std::string &os : orders) {
      const int order = std::atoi(os.c_str());
      const bench::Points pc = box_points(n, cube, 7);
      std::string cw;
      auto ec = chosen(pc, cube, order, cw);
      for (const std::string &bs : boxes) {
        const std::vector<std::string> e = split(bs.c_str(), ':');
        if (e.size() != 3) return 2;
        const Box box{bs, {std::atof(e[0].c_str()), std::atof(e[1].c_str()), std::atof(e[2].c_str())}};
        const bench::Points pb = box_points(n, box, 7);
        std::string bw;
        auto eb = chosen(pb, box, order, bw, box_grid);
        std::vector<double> pot(n), gb(3 * n), gc(3 * n);
        eb->evaluate(n, pb.xyz.data(), pb.q.data(), n, pb.xyz.data(), pot.data(), gb.data());    // operators
        ec->evaluate(n, pc.xyz.data(), pc.q.data(), n, pc.xyz.data(), pot.data(), gc.data());
        double tb = 1e300, tc = 1e300;
        for (int r = 0; r < reps; ++r) {
          double c0 = cpu_now();
          eb->evaluate(n, pb.xyz.data(), pb.q.data(), n, pb.xyz.data(), pot.data(), gb.data());
          tb = std::min(tb, cpu_now() - c0);
          c0 = cpu_now();
          ec->evaluate(n, pc.xyz.data(), pc.q.data(), n, pc.xyz.data(), pot.data(), gc.data());
          tc = std::min(tc, cpu_now() - c0);
        }
        std::printf("| %s | %d | %s | %s | %s | %.2f | %.4f | %.4f | %.1e | %.1e |\n", ns.c_str(), order, bs.c_str(),
                    bw.c_str(), cw.c_str(), tb / tc, tb, tc, sampled_error(*eb, pb, gb, sample),
                    sampled_error(*ec, pc, gc, sample));
        if (phases)
          for (const Evaluator *ev : {eb.get(), ec.get()}) {
            const Stats &st = ev->stats();
            std::printf("|   phases (%s) | upward %.4f | m2l %.4f | downward %.4f | p2p %.4f | cells %zu |\n",
                        ev == eb.get() ? "box" : "cube", st.t_upward, st.t_m2l, st.t_downward, st.t_p2p, st.n_cells);
          }
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
