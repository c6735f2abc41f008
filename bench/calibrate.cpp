// Regenerates the choose_order calibration table (src/KIFMM/engine/calibration.cpp):
// for each order, the leaf size with the smallest evaluation time on the standard
// configuration (20000 uniform random points in a cube, charges in [-1,1], seed 1) and the
// relative RMS force (gradient) error measured there. Usage: calibrate [--kernel yukawa K]
#include "direct_sum.h"
#include "fmm_core.h"
#include "kernels.h"

#include "bench_points.h"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

using namespace kifmm;

int main(int argc, char **argv)
{
  KernelSpec spec;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--kernel") && i + 2 < argc && !std::strcmp(argv[i + 1], "yukawa")) {
      spec.type = KernelType::Yukawa;
      spec.kappa = std::atof(argv[i + 2]);
    }
  const std::size_t n = 20000;
  bench::Points p = bench::uniform(n, 1);
  std::vector<double> rp(n), rg(3 * n);
  direct_sum(spec, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), rp.data(), rg.data());
  std::printf("  // order, leaf size, relative RMS force error (20000 uniform points, %s)\n",
              spec.type == KernelType::Yukawa ? "yukawa" : "laplace");
  for (int order = 3; order <= 14; ++order) {
    int best_leaf = 0;
    double best_t = 1e30, best_err = 0;
    for (int leaf : {64, 128, 192, 256, 384, 512, 768}) {
      Options o;
      o.order = order;
      o.leaf_size = leaf;
      auto ev = make_evaluator(spec, o);
      std::vector<double> pot(n), g(3 * n);
      ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
      double t = 1e30;
      for (int rep = 0; rep < 3; ++rep) {
        const double t0 = omp_get_wtime();
        ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
        t = std::min(t, omp_get_wtime() - t0);
      }
      double num = 0, den = 0;
      for (std::size_t i = 0; i < 3 * n; ++i) {
        num += (g[i] - rg[i]) * (g[i] - rg[i]);
        den += rg[i] * rg[i];
      }
      const double err = std::sqrt(num / den);
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
