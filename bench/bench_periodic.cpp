// Cost of a periodic (p p p) evaluation relative to a free-space one at the same N and order,
// measured in the same run as CPU time of the process (clock_gettime PROCESS_CPUTIME; run with
// OMP_NUM_THREADS=1 on a shared machine); the two are timed alternately, minimum of --reps. Uniform random charges (neutral) in the cube
// [-1,1]^3; the free-space evaluator gets the same cube as fixed root (same octree). Each
// evaluator uses the engine's default leaf size for the order unless --leaves is given (then
// every leaf size is timed and the fastest of each mode is reported). Potential + gradient.
//   bench_periodic [--sizes 1e4,3e4,1e5] [--orders 4,5,6,7,8] [--leaves 64,128,256,512]
//                  [--reps 3] [--phases]
// --phases prints the engine's phase times (wall, single thread) of the best repetition.
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

// Free-space and periodic evaluators at one leaf size, timed alternately (free, periodic,
// free, ...) so that both see the same machine load; minimum CPU time of each.
void time_pair(const bench::Points &p, int order, int leaf, int reps, Timing out[2])
{
  std::unique_ptr<Evaluator> ev[2];
  const std::size_t n = p.size();
  std::vector<double> pot(n), g(3 * n);
  for (int m = 0; m < 2; ++m) {
    Options o;
    o.order = order;
    o.leaf_size = leaf;
    o.fixed_root = true;
    o.root_half_width = 1.0;
    o.periodic = m == 1;
    ev[m] = make_evaluator(KernelSpec{}, o);
    ev[m]->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());    // operators
    out[m] = Timing{};
    out[m].leaf = ev[m]->options().leaf_size;
  }
  for (int r = 0; r < reps; ++r)
    for (int m = 0; m < 2; ++m) {
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
  std::printf("| N | order | free leaf (depth) | free CPU s | periodic leaf (depth) | periodic CPU s | ratio |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (double nd : sizes) {
    const std::size_t n = (std::size_t) nd;
    bench::Points p = bench::uniform(n, 2024);
    double s = 0;
    for (double q : p.q) s += q;
    for (double &q : p.q) q -= s / n;
    for (double od : orders) {
      const int order = (int) od;
      Timing best[2];
      std::vector<int> ls;
      if (leaves.empty()) ls.push_back(0);
      for (double l : leaves) ls.push_back((int) l);
      for (int l : ls) {
        Timing t[2];
        time_pair(p, order, l, reps, t);
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
