// Cost of a periodic (p p p) evaluation relative to a free-space one at the same N and order,
// measured in the same run as CPU time of the process (clock_gettime PROCESS_CPUTIME; run with
// OMP_NUM_THREADS=1 on a shared machine), minimum of --reps. Uniform random charges (neutral)
// in the cube [-1,1]^3; the free-space evaluator gets the same cube as fixed root. Potential +
// gradient, sources = targets.
// Default: four evaluators timed alternately (open and periodic, each at the leaf size of the
// cost model, choose_tree, as kspace_style kifmm uses it, and at the per-order calibrated leaf
// size of the engine default): the table gives the periodic/open ratio at the model's choice
// and each mode's model/calibrated CPU ratio.
// With --leaves every leaf size is timed for both modes (alternately) and the fastest of each
// mode is reported.
//   bench_periodic [--sizes 1e4,3e4,1e5] [--orders 4,5,6,7,8] [--leaves 64,128,256,512]
//                  [--reps 3] [--phases]
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
                Timing *out)
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
    ev[m] = make_evaluator(KernelSpec{}, o);
    ev[m]->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());    // operators
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
  std::vector<double> sizes{1e4, 3e4, 1e5}, orders{4, 5, 6, 7, 8}, leaves;
  int reps = 3;
  bool phases = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--sizes") && i + 1 < argc) sizes = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--orders") && i + 1 < argc) orders = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--leaves") && i + 1 < argc) leaves = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--phases")) phases = true;
    else {
      std::fprintf(stderr, "usage: %s [--sizes ..] [--orders ..] [--leaves ..] [--reps R] [--phases]\n", argv[0]);
      return 1;
    }
  }
  if (leaves.empty()) {
    std::printf("| N | order | open leaf (depth) | open CPU s | periodic leaf (depth) | periodic CPU s | periodic/open |"
                " calibrated leaf (depth open, periodic) | periodic/open calibrated | open model/calibrated |"
                " periodic model/calibrated |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
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
      if (leaves.empty()) {    // model choice (0: open, 1: periodic) and calibrated leaf (2, 3)
        const bool per[4] = {false, true, false, true};
        const int lf[4] = {choose_tree(order, n, false).leaf_size, choose_tree(order, n, true).leaf_size, 0, 0};
        Timing t[4];
        time_modes(p, order, 4, per, lf, reps, t);
        if (phases)
          for (int m = 0; m < 4; ++m) {
            std::printf("    N=%zu p=%d leaf=%d depth=%d %s cpu %.4f\n", n, order, t[m].leaf, t[m].depth,
                        per[m] ? "periodic" : "free", t[m].cpu);
            print_phases(per[m] ? "periodic" : "free", t[m].stats);
          }
        std::printf("| %zu | %d | %d (%d) | %.4f | %d (%d) | %.4f | %.2f | %d (%d, %d) | %.2f | %.2f | %.2f |\n", n,
                    order, t[0].leaf, t[0].depth, t[0].cpu, t[1].leaf, t[1].depth, t[1].cpu, t[1].cpu / t[0].cpu,
                    t[2].leaf, t[2].depth, t[3].depth, t[3].cpu / t[2].cpu, t[0].cpu / t[2].cpu, t[1].cpu / t[3].cpu);
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
