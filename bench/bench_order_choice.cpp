// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The order chosen for a requested accuracy against the error it gives. For each point set and
// request, what kspace_style kifmm does on one rank: the calibrated order (choose_order), the
// tree (plan_tree + choose_tree_from_points), then the order measured on the points
// (bench/measured_order.h: search_order on targets sampled against the direct sum), the tree
// chosen again for a changed order. Reported: the calibrated and the chosen order, the
// error estimate of the search, the true relative RMS gradient error over ALL points against
// the direct sum at the chosen order and at the order below (on the tree chosen for that order,
// as the search evaluates it), and the verdicts: "meets" (true error <= request) and "tight"
// (the order below misses the request, or the chosen error is at most 5x below it; "n/a": the
// order below gives the same error, a direct sum where the order does not act).
//   bench_order_choice [--sets uniform,plummer,clusters] [--sizes 1e4,1e5]
//                      [--requests 1e-3,1e-5,1e-7,1e-10] [--periodic]
// Potential + gradient, sources = targets; periodic: points scaled into the cell [-1,1]^3,
// neutral charges, reference the Ewald sum on the sample and order 14 over all points.
#include "bench_points.h"
#include "measured_order.h"
#include "kifmm.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

namespace {

// relative RMS force error over all points (force_i = q_i grad_i) against the exact gradients
double force_error(const bench::Points &p, const std::vector<double> &grad, const std::vector<double> &exact)
{
  std::vector<double> a(grad.size()), e(grad.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int d = 0; d < 3; ++d) {
      a[3 * i + d] = p.q[i] * grad[3 * i + d];
      e[3 * i + d] = p.q[i] * exact[3 * i + d];
    }
  return bench::relative_difference(a, e);
}

std::vector<double> gradient_at(const bench::Points &p, const kifmm::Options &o)
{
  const std::size_t n = p.size();
  std::vector<double> pot(n), grad(3 * n);
  kifmm::make_evaluator(kifmm::KernelSpec{}, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(),
                                                          grad.data());
  return grad;
}

void one_case(const std::string &name, const bench::Points &p, bool periodic, const std::vector<double> &requests)
{
  const std::size_t n = p.size();
  const kifmm::KernelSpec kernel;
  kifmm::Options base;
  if (periodic) {
    base.periodic = true;
    base.fixed_root = true;
    base.root_half_width = 1.0;
  }
  // the exact gradients of all points: direct sum (open), order 14 (periodic)
  std::vector<double> exact(3 * n), pot(n);
  if (periodic) {
    kifmm::Options o = base;
    o.order = 14;
    o.leaf_size = kifmm::choose_tree(14, n, true).leaf_size;
    exact = gradient_at(p, o);
  } else {
    kifmm::direct_sum(kernel, n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), exact.data());
  }
  std::vector<std::size_t> all(n);
  std::iota(all.begin(), all.end(), 0);
  const std::vector<std::size_t> sample = kifmm::sample_without_replacement(all, kifmm::order_search_samples, 1234567ULL);
  std::vector<double> sample_exact(3 * sample.size());
  for (std::size_t k = 0; k < sample.size(); ++k)
    for (int d = 0; d < 3; ++d) sample_exact[3 * k + d] = exact[3 * sample[k] + d];
  for (double acc : requests) {
    const bench::MeasuredOrder m =
        bench::measured_order(kernel, base, acc, n, p.xyz.data(), p.q.data(), sample, sample_exact);
    const double err = force_error(p, m.grad, exact);
    double below = -1;
    if (m.found.order > 3) {
      kifmm::Options lower = base;
      lower.order = m.found.order - 1;
      const kifmm::TreeRequest tree{n, 0, periodic ? -1 : 0, false};
      lower = kifmm::plan_tree(lower, tree).options;
      kifmm::choose_tree_from_points(kernel, tree, lower, n, p.xyz.data());
      below = force_error(p, gradient_at(p, lower), exact);
    }
    const bool meets = err <= acc;
    const bool moot = below >= 0 && std::fabs(below - err) <= 1e-6 * err;
    const char *tight = moot ? "n/a" : below < 0 || below > acc || err * 5 >= acc ? "yes" : "**no**";
    std::printf("| %s | %zu | %.0e | %d | %d | %.2e | %.2e | %.2e | %s | %s | %d |\n", name.c_str(), n, acc, m.calibrated,
                m.found.order, m.found.error, err, below, meets ? "yes" : "**no**", tight, m.evaluations);
    std::fflush(stdout);
  }
}

}    // namespace

int main(int argc, char **argv)
{
  std::vector<std::string> sets = {"uniform", "plummer", "clusters"};
  std::vector<double> sizes = {1e4, 1e5}, requests = {1e-3, 1e-5, 1e-7, 1e-10};
  bool periodic = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--sets" && i + 1 < argc) sets = bench::split_list(argv[++i]);
    else if (a == "--sizes" && i + 1 < argc) sizes = bench::number_list(argv[++i]);
    else if (a == "--requests" && i + 1 < argc) requests = bench::number_list(argv[++i]);
    else if (a == "--periodic") periodic = true;
    else {
      std::fprintf(stderr, "bench_order_choice: unknown option %s\n", a.c_str());
      return 1;
    }
  }
  std::printf("%s boundaries; error = relative RMS force error over all points against the %s\n\n",
              periodic ? "periodic (cell [-1,1]^3, neutral charges)" : "open",
              periodic ? "order-14 evaluation" : "direct sum");
  std::printf("| points | N | request | order calibrated | order chosen | search estimate | error | error at order - 1 | "
              "meets | tight | evaluations |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (double s : sizes)
    for (const auto &name : sets) {
      const std::size_t n = (std::size_t) s;
      bench::Points p;
      if (name == "uniform") p = kifmm_points::uniform_cube(n, 1);
      else if (name == "plummer") p = kifmm_points::plummer(n, 2);
      else if (name == "clusters") p = kifmm_points::two_clusters(n, 3);
      else {
        std::fprintf(stderr, "bench_order_choice: unknown point set %s\n", name.c_str());
        return 1;
      }
      if (periodic) p = bench::into_periodic_cell(p);
      one_case(name, p, periodic, requests);
    }
  return 0;
}
