// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Engine benchmark: for each configuration and order, times of tree+lists, evaluation,
// operator setup (cold / from the disk cache), the relative force (gradient) error against a
// direct sum on a random sample of targets, the speed-up over the vectorized direct sum
// measured in the same run (full direct time = N^2 / measured direct pairs/s), and the
// near-field throughput. Potential + gradient. The 1-thread CPU time of the chosen setup is
// also measured with the targets passed as a shuffled copy of the sources, which makes the
// engine use the one-sided near field instead of the mutual one (same tree, same work
// otherwise). Usage:
//   bench_engine [--quick] [--orders 4,6,8] [--leaves 128,256,512] [--sizes 1e4,1e5,1e6]
//                [--plummer 1e5] [--reps 3] [--large-orders 6,7,8] [--large-leaves 384,512]
// For each (configuration, order) every leaf size given is timed and the fastest is reported
// (default: the engine's default leaf size for the order).
//
// Tree-choice comparison (bench/run_tree_choice.sh):
//   bench_engine --tree-choice [--sizes 1e3,1e4] [--plummer 1e4] [--data FILE.data,...]
//                [--orders 4,7,9] [--periodic] [--reps 7] [--min-time 0.2]
// For each point set and order, three leaf sizes of the same open (or --periodic: [-1,1]^3
// periodic cell, charges made neutral) N-body evaluation: "old" = the per-order default leaf
// (default_leaf_size, the choice before the cost model), "uniform" = choose_tree(order, n,
// periodic) as at commit c4d85d4 (the uniform-points cost model with that commit's constants,
// leaf_c4d85d4), "points" = choose_tree(kernel, options, n, xyz)
// (the model on the counts of the actual trees). Single-thread CPU time per evaluation, the
// three interleaved in rotating order, --reps rounds (each timed over >= --min-time s); reported:
// medians per variant and the medians over the rounds of the per-round ratios; relative RMS
// force error against the direct sum (all points up to 2e4, else 2000 sampled targets; periodic:
// against order 14, itself checked against the Ewald sum); the time of the choice itself.
// Point sets: --sizes uniform in [-1,1]^3 (bench::uniform); --plummer bench::plummer; --data
// LAMMPS data files with "Atoms # charge" (id type q x y z), e.g. from bench_solvers gen.
#include "cost_model.h"
#include "direct_sum.h"
#include "fmm_core.h"
#include "periodic.h"
#include "kernels.h"
#include "operator_cache.h"
#include "surface.h"

#include "bench_points.h"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <time.h>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
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

struct Row {
  std::string config;
  std::size_t n;
  int order, leaf;
  double t_tree, t_eval, t_pre_cold, t_pre_disk, err, speedup, p2p_rate, direct_rate, t_direct_full;
  double t_up, t_m2l, t_wx, t_down, t_p2p, cpu1, cpu1_one;
  int depth;
  std::size_t leaves;
};

double now() { return omp_get_wtime(); }

double cpu_now()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

std::vector<std::string> split(const char *s)
{
  std::vector<std::string> v;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) v.push_back(tok);
  return v;
}

// choose_tree(order, n, periodic) as it was at commit c4d85d4 (the choice the bench/solvers
// campaign measured): constants of that fit, counts without the self-pair and entry terms
int leaf_c4d85d4(int order, std::size_t n, bool periodic)
{
  static const double k[12][4] = {
      {224, 0.7052, 92.17, 0},          {286.4, 0.6828, 149.9, 232.8},   {380, 0.6811, 211.4, 7037},
      {309.7, 0.7213, 303.1, 2.789e+04}, {584.6, 0.6548, 455.9, 4.707e+04}, {626, 0.6704, 635.1, 7.565e+04},
      {600.8, 0.7151, 770.9, 1.84e+05}, {746, 0.6944, 993, 1.94e+05},    {659.5, 0.7511, 1459, 3.585e+05},
      {345, 0.8486, 1752, 4.624e+05},   {0, 0.9459, 2013, 6.522e+05},    {0, 0.9564, 2880, 8.386e+05}};
  const double *c = k[std::min(std::max(order, 3), 14) - 3];
  auto cost = [&](int d) {
    const TreeCounts t = uniform_tree_counts(n, d, periodic);
    return c[0] * n + c[1] * t.near_pairs + c[2] * t.translations + c[3] * t.cells;
  };
  int best = 0;
  for (int d = 1; d <= 20 && std::ldexp(1.0, 3 * d) <= (double) n; ++d)
    if (cost(d) < cost(best)) best = d;
  return leaf_size_for_depth(n, best);
}

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const std::size_t k = v.size();
  return k % 2 ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
}

int tree_choice(int argc, char **argv)
{
  std::vector<double> orders = {4, 7, 9}, sizes = {1e3, 3e3, 1e4, 1e5}, plum = {1e4, 1e5};
  std::vector<std::string> files;
  int reps = 7;
  double min_time = 0.2;
  bool periodic = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--orders") && i + 1 < argc) orders = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--sizes") && i + 1 < argc) sizes = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--plummer") && i + 1 < argc) plum = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--data") && i + 1 < argc) files = split(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--min-time") && i + 1 < argc) min_time = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--periodic")) periodic = true;
  }
  omp_set_num_threads(1);
  std::vector<bench::NamedPoints> cfgs = bench::uniform_and_plummer(sizes, plum);
  for (const std::string &f : files) {
    std::string name = std::filesystem::path(f).stem().string();
    cfgs.push_back({name, bench::read_charge_data(f)});
  }
  const char *variant[3] = {"old", "uniform", "points"};
  std::printf("| points | N | p | leaf old / uniform / points | depth old / uniform / points | CPU s per evaluation old / uniform / points (medians) | points/old | points/uniform | uniform/old | force error old / uniform / points | choice s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);
  for (bench::NamedPoints &cfg : cfgs) {
    const std::size_t n = cfg.pts.size();
    Options base;
    base.max_depth = 20;
    if (periodic) {
      // the points in the periodic cell [-1,1]^3 (scaled from their bounding cube), neutral
      RootBox bb = bounding_cube(n, cfg.pts.xyz.data(), n, cfg.pts.xyz.data());
      for (std::size_t i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d)
          cfg.pts.xyz[3 * i + d] = (cfg.pts.xyz[3 * i + d] - bb.center[d]) / bb.half_width;
      double s = 0;
      for (double q : cfg.pts.q) s += q;
      for (double &q : cfg.pts.q) q -= s / n;
      base.fixed_root = true;
      base.root_half_width = 1.0;
      base.periodic = true;
    }
    const double *x = cfg.pts.xyz.data(), *q = cfg.pts.q.data();
    // reference: direct sum (open) or order 14 (periodic), on all points up to 2e4
    const std::size_t ns = n <= 20000 ? n : 2000;
    std::vector<std::size_t> sample(n);
    for (std::size_t i = 0; i < n; ++i) sample[i] = i;
    if (ns < n) {
      std::mt19937_64 g(99);
      std::shuffle(sample.begin(), sample.end(), g);
      sample.resize(ns);
    }
    std::vector<double> ref(3 * ns);
    {
      omp_set_num_threads(2);
      std::vector<double> sx(3 * ns), rp(ns);
      for (std::size_t i = 0; i < ns; ++i)
        for (int d = 0; d < 3; ++d) sx[3 * i + d] = x[3 * sample[i] + d];
      if (periodic) {
        Options o = base;
        o.order = 14;
        o.leaf_size = choose_tree(14, n, true).leaf_size;
        std::vector<double> pot(n), gr(3 * n);
        make_evaluator(KernelSpec{}, o)->evaluate(n, x, q, n, x, pot.data(), gr.data());
        for (std::size_t i = 0; i < ns; ++i)
          for (int d = 0; d < 3; ++d) ref[3 * i + d] = gr[3 * sample[i] + d];
        const std::size_t ne = std::min<std::size_t>(ns, 100);
        std::vector<double> ep(ne), eg(3 * ne);
        const double c0[3] = {0, 0, 0};
        periodic_direct_sum(KernelSpec{}, c0, 1.0, n, x, q, ne, sx.data(), ep.data(), eg.data());
        double num = 0, den = 0;
        for (std::size_t i = 0; i < 3 * ne; ++i) {
          num += (ref[i] - eg[i]) * (ref[i] - eg[i]);
          den += eg[i] * eg[i];
        }
        std::fprintf(stderr, "%s N=%zu: order-14 reference vs Ewald on %zu targets %.2e\n", cfg.name.c_str(), n, ne,
                     std::sqrt(num / den));
      } else {
        direct_sum(KernelSpec{}, n, x, q, ns, sx.data(), rp.data(), ref.data());
      }
      omp_set_num_threads(1);
    }
    for (double od : orders) {
      const int order = (int) od;
      Options o = base;
      o.order = order;
      int leaf[3];
      leaf[0] = default_leaf_size(order);
      leaf[1] = leaf_c4d85d4(order, n, periodic);
      double c0 = cpu_now();
      const TreeChoice pc = choose_tree(KernelSpec{}, o, n, x);
      const double t_choice = cpu_now() - c0;
      leaf[2] = pc.leaf_size;
      std::unique_ptr<FmmEvaluator<LaplaceKernel>> ev[3];
      std::vector<double> pot(n), grad(3 * n);
      double err[3];
      int depth[3];
      for (int v = 0; v < 3; ++v) {
        o.leaf_size = leaf[v];
        ev[v] = std::make_unique<FmmEvaluator<LaplaceKernel>>(LaplaceKernel{}, KernelSpec{}, o);
        ev[v]->evaluate(n, x, q, n, x, pot.data(), grad.data());    // operators, error
        depth[v] = ev[v]->stats().depth;
        err[v] = bench::sampled_relative_rms(grad, sample, ref);
      }
      // evaluations per timing: >= min_time s (from one timed evaluation of the old tree)
      c0 = cpu_now();
      ev[0]->evaluate(n, x, q, n, x, pot.data(), grad.data());
      const int inner = std::max(1, (int) std::ceil(min_time / std::max(1e-6, cpu_now() - c0)));
      std::vector<double> t[3], r_po, r_pu, r_uo;
      for (int rep = 0; rep < reps; ++rep) {
        double tr[3];
        for (int k = 0; k < 3; ++k) {
          const int v = (rep + k) % 3;    // rotating order
          c0 = cpu_now();
          for (int i = 0; i < inner; ++i) ev[v]->evaluate(n, x, q, n, x, pot.data(), grad.data());
          tr[v] = (cpu_now() - c0) / inner;
          t[v].push_back(tr[v]);
        }
        r_po.push_back(tr[2] / tr[0]);
        r_pu.push_back(tr[2] / tr[1]);
        r_uo.push_back(tr[1] / tr[0]);
      }
      std::printf("| %s | %zu | %d | %d / %d / %d | %d / %d / %d | %.4g / %.4g / %.4g | %.2f | %.2f | %.2f | %.2e / %.2e / %.2e | %.3g |\n",
                  cfg.name.c_str(), n, order, leaf[0], leaf[1], leaf[2], depth[0], depth[1], depth[2], median(t[0]),
                  median(t[1]), median(t[2]), median(r_po), median(r_pu), median(r_uo), err[0], err[1], err[2],
                  t_choice);
      std::fflush(stdout);
      for (int v = 0; v < 3; ++v) {
        o.leaf_size = leaf[v];
        const TreeChoice m = model_tree(KernelSpec{}, o, n, x, leaf[v]);
        std::fprintf(stderr, "  %s %s N=%zu p=%d leaf %d depth %d: modelled %.4g s, measured %.4g s\n", cfg.name.c_str(),
                     variant[v], n, order, leaf[v], m.depth, m.cost, median(t[v]));
      }
      const TreeChoice un = choose_tree(order, n, periodic);
      std::fprintf(stderr, "  (uniform model with this commit's constants: leaf %d depth %d; choice from the points: %.3g s)\n",
                   un.leaf_size, un.depth, t_choice);
    }
  }
  return 0;
}

}    // namespace

int main(int argc, char **argv)
{
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--tree-choice")) return tree_choice(argc, argv);
  std::vector<double> orders = {4, 6, 7, 8, 10, 12}, large_orders = {6, 7, 8}, sizes = {1e4, 1e5, 1e6}, plum = {1e5};
  std::vector<double> leaves_large;
  std::vector<double> leaves = {0};
  int reps = 3;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--orders") && i + 1 < argc) orders = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--sizes") && i + 1 < argc) sizes = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--plummer") && i + 1 < argc) plum = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--leaves") && i + 1 < argc) leaves = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--large-orders") && i + 1 < argc) large_orders = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--large-leaves") && i + 1 < argc) leaves_large = parse_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--quick")) {
      orders = {6};
      sizes = {1e4, 1e5};
      plum = {};
    }
  }
  std::vector<bench::NamedPoints> cfgs = bench::uniform_and_plummer(sizes, plum);

  const std::string cache_dir = (std::filesystem::temp_directory_path() / ("kifmm_bench_" + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(cache_dir);
  std::vector<Row> rows;
  std::vector<int> cold_done;
  for (auto &cfg : cfgs) {
    const std::size_t n = cfg.pts.size();
    const double *x = cfg.pts.xyz.data(), *q = cfg.pts.q.data();
    // direct-sum reference on a random sample of targets
    const std::size_t ns = std::min<std::size_t>(n, 2000);
    std::vector<std::size_t> sample(n);
    for (std::size_t i = 0; i < n; ++i) sample[i] = i;
    std::mt19937_64 g(99);
    std::shuffle(sample.begin(), sample.end(), g);
    sample.resize(ns);
    std::vector<double> sx(3 * ns), rp(ns), rg(3 * ns);
    for (std::size_t i = 0; i < ns; ++i)
      for (int d = 0; d < 3; ++d) sx[3 * i + d] = x[3 * sample[i] + d];
    double t0 = now();
    direct_sum_t(LaplaceKernel{}, n, x, q, ns, sx.data(), rp.data(), rg.data());
    const double t_dir = now() - t0;
    const double direct_rate = double(n) * ns / t_dir;
    const bool large = n >= 500000;    // N >= 5e5: --large-orders / --large-leaves
    for (double od : (large ? large_orders : orders)) {
      const int order = (int) od;
      Options o;
      o.order = order;
      o.leaf_size = (int) leaves[0];
      o.cache_dir = cache_dir;
      Row r{};
      r.config = cfg.name;
      r.n = n;
      r.order = order;
      r.t_pre_cold = r.t_pre_disk = -1;
      if (std::find(cold_done.begin(), cold_done.end(), order) == cold_done.end()) {
        // operator setup: cold (computed, written) then from disk
        clear_operator_memory_cache();
        std::filesystem::remove(operator_cache_file(cache_dir, "laplace", order));
        FmmEvaluator<LaplaceKernel> e1(LaplaceKernel{}, KernelSpec{}, o);
        std::vector<double> p1(n), g1(3 * n);
        e1.evaluate(n, x, q, n, x, p1.data(), g1.data());
        r.t_pre_cold = e1.stats().t_precompute;
        clear_operator_memory_cache();
        FmmEvaluator<LaplaceKernel> e2(LaplaceKernel{}, KernelSpec{}, o);
        e2.evaluate(n, x, q, n, x, p1.data(), g1.data());
        r.t_pre_disk = e2.stats().t_precompute;
        cold_done.push_back(order);
      }
      std::unique_ptr<FmmEvaluator<LaplaceKernel>> best_ev;
      std::vector<double> pot(n), grad(3 * n);
      double best = 1e30;
      Stats st;
      for (double lf : (large && !leaves_large.empty() ? leaves_large : leaves)) {
        o.leaf_size = (int) lf;
        auto ev = std::make_unique<FmmEvaluator<LaplaceKernel>>(LaplaceKernel{}, KernelSpec{}, o);
        ev->evaluate(n, x, q, n, x, pot.data(), grad.data());    // warm (operators in memory)
        bool improved = false;
        for (int rep = 0; rep < reps; ++rep) {
          t0 = now();
          ev->evaluate(n, x, q, n, x, pot.data(), grad.data());
          const double t = now() - t0;
          if (t < best) {
            best = t;
            st = ev->stats();
            improved = true;
          }
        }
        if (improved) best_ev = std::move(ev);
      }
      FmmEvaluator<LaplaceKernel> &ev = *best_ev;
      {
        // single-thread CPU time of the chosen setup: a load-independent cost measure
        const int saved = omp_get_max_threads();
        omp_set_num_threads(1);
        r.cpu1 = 1e30;
        for (int rep = 0; rep < 2; ++rep) {
          const std::clock_t c0 = std::clock();
          ev.evaluate(n, x, q, n, x, pot.data(), grad.data());
          r.cpu1 = std::min(r.cpu1, double(std::clock() - c0) / CLOCKS_PER_SEC);
        }
        // the same with the one-sided near field (targets: a shuffled copy of the points)
        std::vector<std::size_t> perm(n);
        for (std::size_t i = 0; i < n; ++i) perm[i] = i;
        std::mt19937_64 gp(7);
        std::shuffle(perm.begin(), perm.end(), gp);
        std::vector<double> txyz(3 * n), tp(n), tg(3 * n);
        for (std::size_t i = 0; i < n; ++i)
          for (int d = 0; d < 3; ++d) txyz[3 * i + d] = x[3 * perm[i] + d];
        r.cpu1_one = 1e30;
        for (int rep = 0; rep < 2; ++rep) {
          const std::clock_t c0 = std::clock();
          ev.evaluate(n, x, q, n, txyz.data(), tp.data(), tg.data());
          r.cpu1_one = std::min(r.cpu1_one, double(std::clock() - c0) / CLOCKS_PER_SEC);
        }
        omp_set_num_threads(saved);
      }
      ev.evaluate(n, x, q, n, x, pot.data(), grad.data());    // results of the chosen leaf size
      r.leaf = ev.options().leaf_size;
      r.t_tree = st.t_tree + st.t_lists;
      r.t_eval = best;
      r.t_up = st.t_upward;
      r.t_m2l = st.t_m2l;
      r.t_wx = st.t_wx;
      r.t_down = st.t_downward;
      r.t_p2p = st.t_p2p;
      r.depth = st.depth;
      r.leaves = st.n_leaves;
      double num = 0, den = 0;
      for (std::size_t i = 0; i < ns; ++i)
        for (int d = 0; d < 3; ++d) {
          const double a = grad[3 * sample[i] + d], b = rg[3 * i + d];
          num += (a - b) * (a - b);
          den += b * b;
        }
      r.err = std::sqrt(num / den);
      // near-field pairs: U lists of target leaves
      const auto &tr = ev.tree();
      const auto &li = ev.lists();
      double pairs = 0;
      for (int b : tr.leaves)
        for (const int *a = li.U.begin(b); a != li.U.end(b); ++a)
          pairs += double(tr.cells[b].n_trg()) * tr.cells[*a].n_src();
      // the mutual near field also takes the direct W/X pairs of small leaves (both directions)
      const int nsurf = surface_size(order);
      if (st.mutual_pairs > 0)
        for (int b : tr.leaves)
          for (const int *a = li.W.begin(b); a != li.W.end(b); ++a) {
            const Cell &A = tr.cells[*a];
            if (A.leaf() && (int) A.gtrg <= nsurf && (int) A.gsrc <= nsurf)
              pairs += 2.0 * tr.cells[b].n_trg() * A.n_src();
          }
      r.p2p_rate = pairs / st.t_p2p;
      r.direct_rate = direct_rate;
      r.t_direct_full = double(n) * n / direct_rate;
      r.speedup = r.t_direct_full / r.t_eval;
      rows.push_back(r);
      std::fprintf(stderr, "%s N=%zu p=%d leaf=%d: eval %.3f s err %.2e\n", r.config.c_str(), n, order, r.leaf, r.t_eval, r.err);
    }
  }
  std::filesystem::remove_all(cache_dir);
  std::printf("| config | N | p | leaf | depth | tree+lists s | eval s | 1-thread CPU s | one-sided near field: 1-thread CPU s | up | M2L | W+X | down+L2P | P2P | precompute cold / disk s | rel. force err | direct (est.) s | speed-up | P2P pairs/s | direct pairs/s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Row &r : rows) {
    char pre[64];
    if (r.t_pre_cold >= 0) std::snprintf(pre, sizeof pre, "%.3f / %.3f", r.t_pre_cold, r.t_pre_disk);
    else std::snprintf(pre, sizeof pre, "(cached)");
    std::printf("| %s | %.0e | %d | %d | %d | %.4f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %s | %.2e | %.2f | %.1f | %.2e | %.2e |\n",
                r.config.c_str(), (double) r.n, r.order, r.leaf, r.depth, r.t_tree, r.t_eval, r.cpu1, r.cpu1_one, r.t_up, r.t_m2l, r.t_wx,
                r.t_down, r.t_p2p, pre, r.err, r.t_direct_full, r.speedup, r.p2p_rate, r.direct_rate);
  }
  return 0;
}
