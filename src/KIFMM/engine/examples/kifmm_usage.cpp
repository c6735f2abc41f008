// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Usage of the KIFMM engine through its public interface (kifmm.h) only: N random charges in
// a cube, the order for a requested accuracy (choose_order), one N-body evaluation (potential
// and gradient of every point), and its relative RMS gradient error against the exact direct
// sum. Exit status 1 when the error is above the requested accuracy.
//   kifmm_usage [n_points=20000] [accuracy=1e-5]
#include "kifmm.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

int main(int argc, char **argv)
{
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 20000;
  const double accuracy = argc > 2 ? std::strtod(argv[2], nullptr) : 1e-5;

  // points in [-1, 1]^3 (x y z interleaved) and charges in [-1, 1]
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> xyz(3 * n), q(n);
  for (double &x : xyz) x = u(rng);
  for (double &c : q) c = u(rng);

  // Laplace kernel 1/r; the order whose calibrated force error meets the request
  const kifmm::KernelSpec kernel{kifmm::KernelType::Laplace, 0.0};
  const kifmm::Choice choice = kifmm::choose_order(kernel, accuracy);
  kifmm::Options options;
  options.order = choice.order;
  options.leaf_size = choice.leaf_size;
  auto fmm = kifmm::make_evaluator(kernel, options);

  // N-body: the sources are the targets (same arrays); grad = d pot / d x (not the force)
  std::vector<double> pot(n), grad(3 * n);
  fmm->evaluate(n, xyz.data(), q.data(), n, xyz.data(), pot.data(), grad.data());
  const kifmm::Stats &s = fmm->stats();

  // exact reference, same conventions (pairs at r = 0 excluded)
  std::vector<double> pot_ref(n), grad_ref(3 * n);
  kifmm::direct_sum(kernel, n, xyz.data(), q.data(), n, xyz.data(), pot_ref.data(), grad_ref.data());
  double diff2 = 0.0, ref2 = 0.0;
  for (std::size_t i = 0; i < 3 * n; ++i) {
    diff2 += (grad[i] - grad_ref[i]) * (grad[i] - grad_ref[i]);
    ref2 += grad_ref[i] * grad_ref[i];
  }
  const double error = kifmm::relative_rms(diff2, ref2);

  std::printf("points %zu, order %d, leaf size %d, depth %d, leaves %zu\n", n, options.order, options.leaf_size,
              s.depth, s.n_leaves);
  std::printf("time: tree %.3f s, lists %.3f s, upward %.3f s, M2L %.3f s, near field %.3f s\n", s.t_tree,
              s.t_lists, s.t_upward, s.t_m2l, s.t_p2p);
  std::printf("relative RMS gradient error %.3e (requested %.1e, calibrated %.1e)\n", error, accuracy,
              choice.measured_error);
  if (!(error <= accuracy)) {
    std::printf("FAILED: error above the requested accuracy\n");
    return 1;
  }
  std::printf("OK\n");
  return 0;
}
