// Regenerates the choose_order calibration table of src/KIFMM/engine/calibration.cpp.
// Standard configuration: 100000 uniform random points in a cube, charges uniform in [-1,1]
// (bench::uniform(100000, 1)), Laplace, potential + gradient; error = relative RMS error of
// the gradient (force) on 2000 random targets against the direct sum. For each order the leaf
// size with the smallest single-thread CPU time (robust to other load on the machine) is kept.
// Usage (what produced the table):  OMP_NUM_THREADS=1 ./bench/calibrate > table.txt
#include "direct_sum.h"
#include "fmm_core.h"
#include "kernels.h"

#include "bench_points.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>

using namespace kifmm;

int main()
{
  const std::size_t n = 100000, ns = 2000;
  bench::Points p = bench::uniform(n, 1);
  std::vector<std::size_t> sample(n);
  for (std::size_t i = 0; i < n; ++i) sample[i] = i;
  std::mt19937_64 g(99);
  std::shuffle(sample.begin(), sample.end(), g);
  sample.resize(ns);
  std::vector<double> tx(3 * ns), rp(ns), rg(3 * ns);
  for (std::size_t i = 0; i < ns; ++i)
    for (int d = 0; d < 3; ++d) tx[3 * i + d] = p.xyz[3 * sample[i] + d];
  direct_sum(KernelSpec{}, n, p.xyz.data(), p.q.data(), ns, tx.data(), rp.data(), rg.data());
  std::printf("    // order, leaf size, relative RMS force error   (single-thread CPU s of one evaluation)\n");
  for (int order = 3; order <= 14; ++order) {
    int best_leaf = 0;
    double best_t = 1e30, best_err = 0;
    for (int leaf : {64, 128, 256, 512}) {
      Options o;
      o.order = order;
      o.leaf_size = leaf;
      auto ev = make_evaluator(KernelSpec{}, o);
      std::vector<double> pot(n), gr(3 * n);
      ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), gr.data());    // setup
      double t = 1e30;
      for (int rep = 0; rep < 2; ++rep) {
        const std::clock_t c0 = std::clock();
        ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), gr.data());
        t = std::min(t, double(std::clock() - c0) / CLOCKS_PER_SEC);
      }
      double num = 0, den = 0;
      for (std::size_t i = 0; i < ns; ++i)
        for (int d = 0; d < 3; ++d) {
          const double a = gr[3 * sample[i] + d], b = rg[3 * i + d];
          num += (a - b) * (a - b);
          den += b * b;
        }
      const double err = std::sqrt(num / den);
      std::fprintf(stderr, "order %d leaf %d: %.3f s, error %.2e\n", order, leaf, t, err);
      if (t < best_t) {
        best_t = t;
        best_leaf = leaf;
        best_err = err;
      }
    }
    std::printf("    {%d, %d, %.2e},    // %.3f s\n", order, best_leaf, best_err, best_t);
    std::fflush(stdout);
  }
  return 0;
}
