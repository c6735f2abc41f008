// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Cost of a periodic (p p p) evaluation relative to a free-space one at the same N and order,
// measured in the same run as CPU time of the process (clock_gettime PROCESS_CPUTIME; run with
// OMP_NUM_THREADS=1), minimum of --reps. Uniform random charges (neutral)
// in the cube [-1,1]^3; the free-space evaluator gets the same cube as fixed root. Potential +
// gradient, sources = targets.
// Default: the trees kspace_style kifmm chooses on one rank from the points (choose_tree(kernel,
// options, n, xyz): open, and periodic, which may be the single-level grid of periodic_grid.h)
// and the periodic octree of that choice without the grid, timed alternately: the table gives
// the periodic/open ratio of the choices and of the octree alone. --errors adds the relative
// RMS gradient error of each (all points) against the octree at order 13 of the same boundary
// (periodic: agrees with the Ewald sum to ~3e-11; open: the calibration's order-14 error is
// 7e-12), computed once per row outside the timings.
// With --leaves every leaf size is timed for both modes (alternately) and the fastest of each
// mode is reported.
// With --grids the periodic single-level grids of k^3 cells (periodic_grid.h) are timed beside
// the open and periodic octree evaluations at the model's leaf size (all alternately).
//   bench_periodic [--sizes 1e4,3e4,1e5] [--orders 4,5,6,7,8] [--leaves 64,128,256,512]
//                  [--grids 4,5,6,7] [--reps 3] [--phases] [--errors]
// --phases prints the engine's phase times (wall, single thread) of the best repetition.
#include "cost_model.h"
#include "fmm_core.h"
#include "kifmm.h"

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

std::vector<double> parse_list(const char *s)
{
  std::vector<double> v;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) v.push_back(std::atof(tok.c_str()));
  return v;
}

double cpu_now()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

struct Timing {
  double cpu = 1e300;
  int leaf = 0, depth = 0;
  Stats stats;
};

// Evaluators (mode k: periodic[k], leaf[k]; 0 = engine default) timed alternately (0, 1, ...,
// 0, 1, ...) so that all see the same machine load; minimum CPU time of each.
void time_modes(const bench::Points &p, int order, int nm, const bool *periodic, const int *leaf, int reps,
                Timing *out, const int *grid = nullptr, std::vector<double> *grads = nullptr)
{
  std::vector<std::unique_ptr<Evaluator>> ev(nm);
  const std::size_t n = p.size();
  std::vector<double> pot(n), g(3 * n);
  for (int m = 0; m < nm; ++m) {
    Options o;
    o.order = order;
    o.leaf_size = leaf[m];
    o.fixed_root = true;
    o.root_half_width = 1.0;
    o.periodic = periodic[m];
    o.periodic_grid = grid ? grid[m] : 0;
    ev[m] = make_evaluator(KernelSpec{}, o);
    ev[m]->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());    // operators
    if (grads) grads[m] = g;
    out[m] = Timing{};
    out[m].leaf = ev[m]->options().leaf_size;
  }
  for (int r = 0; r < reps; ++r)
    for (int m = 0; m < nm; ++m) {
      const double c0 = cpu_now();
      ev[m]->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
      const double c = cpu_now() - c0;
      if (c < out[m].cpu) {
        out[m].cpu = c;
        out[m].stats = ev[m]->stats();
        out[m].depth = out[m].stats.depth;
      }
    }
}

void print_phases(const char *mode, const Stats &s)
{
  std::printf("      %-8s tree %.3f lists %.3f up %.3f m2l %.3f wx %.3f down %.3f p2p %.3f\n", mode, s.t_tree,
              s.t_lists, s.t_upward, s.t_m2l, s.t_wx, s.t_downward, s.t_p2p);
}

}    // namespace

int main(int argc, char **argv)
{
  std::vector<double> sizes{1e4, 3e4, 1e5}, orders{4, 5, 6, 7, 8}, leaves, grids;
  int reps = 3;
  bool phases = false, errors = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--sizes") && i + 1 < argc) sizes = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--orders") && i + 1 < argc) orders = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--leaves") && i + 1 < argc) leaves = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--grids") && i + 1 < argc) grids = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--phases")) phases = true;
    else if (!std::strcmp(argv[i], "--errors")) errors = true;
    else {
      std::fprintf(stderr, "usage: %s [--sizes ..] [--orders ..] [--leaves ..] [--grids ..] [--reps R] [--phases] [--errors]\n", argv[0]);
      return 1;
    }
  }
  if (!grids.empty()) {
    std::printf("| N | order | open CPU s (depth) | periodic octree CPU s (depth) | octree/open |");
    for (double k : grids) std::printf(" grid %d CPU s | grid %d/open |", (int) k, (int) k);
    std::printf("\n|---|---|---|---|---|");
    for (std::size_t i = 0; i < grids.size(); ++i) std::printf("---|---|");
    std::printf("\n");
  } else if (leaves.empty()) {
    std::printf("| N | order | open leaf (depth) | open CPU s | periodic choice | periodic CPU s | periodic/open |"
                " periodic octree leaf (depth) | periodic octree CPU s | octree/open |%s\n",
                errors ? " open error | periodic choice error | periodic octree error |" : "");
    std::printf("|---|---|---|---|---|---|---|---|---|---|%s\n", errors ? "---|---|---|" : "");
  } else {
    std::printf("| N | order | free leaf (depth) | free CPU s | periodic leaf (depth) | periodic CPU s | ratio |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
  }
  for (double nd : sizes) {
    const std::size_t n = (std::size_t) nd;
    bench::Points p = bench::uniform(n, 2024);
    double s = 0;
    for (double q : p.q) s += q;
    for (double &q : p.q) q -= s / n;
    for (double od : orders) {
      const int order = (int) od;
      if (!grids.empty()) {    // 0: open, 1: periodic octree (model leaf), 2..: periodic grids
        const int nm = 2 + (int) grids.size();
        std::vector<char> per(nm, 1);
        per[0] = 0;
        std::vector<int> lf(nm, 0), gr(nm, 0);
        lf[0] = choose_tree(order, n, false).leaf_size;
        lf[1] = choose_tree(order, n, true).leaf_size;
        for (std::size_t i = 0; i < grids.size(); ++i) gr[2 + i] = (int) grids[i];
        std::vector<Timing> t(nm);
        bool perb[64];
        for (int m = 0; m < nm; ++m) perb[m] = per[m];
        time_modes(p, order, nm, perb, lf.data(), reps, t.data(), gr.data());
        if (phases)
          for (int m = 0; m < nm; ++m) {
            std::printf("    N=%zu p=%d %s grid %d cpu %.4f\n", n, order, per[m] ? "periodic" : "free", gr[m], t[m].cpu);
            print_phases(per[m] ? "periodic" : "free", t[m].stats);
          }
        std::printf("| %zu | %d | %.4f (%d) | %.4f (%d) | %.2f |", n, order, t[0].cpu, t[0].depth, t[1].cpu, t[1].depth,
                    t[1].cpu / t[0].cpu);
        for (int m = 2; m < nm; ++m) std::printf(" %.4f | %.2f |", t[m].cpu, t[m].cpu / t[0].cpu);
        std::printf("\n");
        std::fflush(stdout);
        continue;
      }
      if (leaves.empty()) {    // the choices of kspace_style kifmm on one rank (from the points),
                               // and the periodic octree of that choice without the grid
        Options oo, op;
        oo.order = op.order = order;
        oo.fixed_root = op.fixed_root = true;
        op.periodic = true;
        const TreeChoice co = choose_tree(KernelSpec{}, oo, n, p.xyz.data());
        const TreeChoice cp = choose_tree(KernelSpec{}, op, n, p.xyz.data());
        const bool per[3] = {false, true, true};
        const int lf[3] = {co.leaf_size, cp.leaf_size, cp.leaf_size}, gr[3] = {0, cp.grid, 0};
        Timing t[3];
        std::vector<double> g[3];
        time_modes(p, order, 3, per, lf, reps, t, gr, errors ? g : nullptr);
        double err[3] = {-1, -1, -1};
        if (errors) {    // against the periodic octree at order 13 (agrees with Ewald to ~3e-11)
          Options o;
          o.order = 13;
          o.fixed_root = true;
          o.periodic = true;
          o.leaf_size = choose_tree(13, n, true).leaf_size;
          std::vector<double> rg(3 * n);
          make_evaluator(KernelSpec{}, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), nullptr, rg.data());
          o.periodic = false;
          std::vector<double> ro(3 * n);
          make_evaluator(KernelSpec{}, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), nullptr, ro.data());
          for (int m = 0; m < 3; ++m) {
            const std::vector<double> &r = per[m] ? rg : ro;
            double num = 0, den = 0;
            for (std::size_t i = 0; i < r.size(); ++i) {
              num += (g[m][i] - r[i]) * (g[m][i] - r[i]);
              den += r[i] * r[i];
            }
            err[m] = std::sqrt(num / den);
          }
        }
        if (phases)
          for (int m = 0; m < 3; ++m) {
            std::printf("    N=%zu p=%d leaf=%d grid=%d depth=%d %s cpu %.4f\n", n, order, t[m].leaf, gr[m], t[m].depth,
                        per[m] ? "periodic" : "free", t[m].cpu);
            print_phases(per[m] ? "periodic" : "free", t[m].stats);
          }
        char pc[64];
        if (cp.grid > 0) std::snprintf(pc, sizeof pc, "grid %d^3", cp.grid);
        else std::snprintf(pc, sizeof pc, "leaf %d (%d)", t[1].leaf, t[1].depth);
        std::printf("| %zu | %d | %d (%d) | %.4f | %s | %.4f | %.2f | %d (%d) | %.4f | %.2f |", n, order, t[0].leaf,
                    t[0].depth, t[0].cpu, pc, t[1].cpu, t[1].cpu / t[0].cpu, t[2].leaf, t[2].depth, t[2].cpu,
                    t[2].cpu / t[0].cpu);
        if (errors) std::printf(" %.2e | %.2e | %.2e |", err[0], err[1], err[2]);
        std::printf("\n");
        std::fflush(stdout);
        continue;
      }
      Timing best[2];
      std::vector<int> ls;
      for (double l : leaves) ls.push_back((int) l);
      for (int l : ls) {
        Timing t[2];
        const bool per[2] = {false, true};
        const int lf[2] = {l, l};
        time_modes(p, order, 2, per, lf, reps, t);
        for (int m = 0; m < 2; ++m) {
          if (phases) {
            std::printf("    N=%zu p=%d leaf=%d depth=%d %s cpu %.4f\n", n, order, t[m].leaf, t[m].depth,
                        m ? "periodic" : "free", t[m].cpu);
            print_phases(m ? "periodic" : "free", t[m].stats);
          }
          if (t[m].cpu < best[m].cpu) best[m] = t[m];
        }
      }
      std::printf("| %zu | %d | %d (%d) | %.4f | %d (%d) | %.4f | %.2f |\n", n, order, best[0].leaf, best[0].depth,
                  best[0].cpu, best[1].leaf, best[1].depth, best[1].cpu, best[1].cpu / best[0].cpu);
      std::fflush(stdout);
    }
  }
  return 0;
}
