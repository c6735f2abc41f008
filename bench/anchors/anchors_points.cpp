// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Writes the problem file of the anchor benchmark (anchors_problem.h): the points of a named set
// (kifmm_point_sets.h) with charges uniform in [-1, 1], a random sample of target indices and the
// exact gradient there (kifmm::direct_sum over all points, double precision, r = 0 excluded).
//   uniform: uniform in the unit cube [0, 1)^3 (seed 1)
//   plummer: Plummer sphere of scale 0.05 centred in the unit cube, radii cut at 0.45 (seed 2)
// Usage: anchors_points uniform|plummer N OUT_FILE [SAMPLES=2000]
#include "anchors_problem.h"
#include "kifmm.h"
#include "kifmm_point_sets.h"

#include <random>

int main(int argc, char **argv)
{
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s uniform|plummer N OUT_FILE [SAMPLES=2000]\n", argv[0]);
    return 2;
  }
  const std::string set = argv[1];
  const std::size_t n = (std::size_t) std::stod(argv[2]);
  const std::size_t ns = argc > 4 ? (std::size_t) std::stod(argv[4]) : 2000;
  anchors::Problem p;
  p.set = set;
  p.n = n;
  kifmm_points::Points pts;
  unsigned seed = 0;
  if (set == "uniform") {
    seed = 1;
    pts = kifmm_points::uniform_cube(n, seed, 0.5);
    for (double &x : pts.xyz) x += 0.5;
  } else if (set == "plummer") {
    seed = 2;
    pts = kifmm_points::plummer_box(n, seed, 0.05);
    std::mt19937_64 g(seed + 1000);
    std::uniform_real_distribution<double> uq(-1.0, 1.0);
    for (double &q : pts.q) q = uq(g);
  } else {
    std::fprintf(stderr, "%s: unknown point set %s (uniform, plummer)\n", argv[0], set.c_str());
    return 2;
  }
  for (double x : pts.xyz)
    if (!(x >= 0.0 && x < 1.0)) {
      std::fprintf(stderr, "%s: a point is outside [0, 1)^3\n", argv[0]);
      return 1;
    }
  p.xyz = std::move(pts.xyz);
  p.q = std::move(pts.q);
  std::vector<std::size_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = i;
  const std::vector<std::size_t> s = kifmm::sample_without_replacement(all, ns, seed + 2000);
  p.sample.assign(s.begin(), s.end());
  std::vector<double> txyz(3 * s.size()), pot(s.size());
  for (std::size_t i = 0; i < s.size(); ++i)
    for (int d = 0; d < 3; ++d) txyz[3 * i + d] = p.xyz[3 * s[i] + d];
  p.ref_grad.assign(3 * s.size(), 0.0);
  kifmm::direct_sum(kifmm::KernelSpec{}, n, p.xyz.data(), p.q.data(), s.size(), txyz.data(), pot.data(),
                    p.ref_grad.data());
  anchors::write_problem(argv[3], p);
  std::printf("%s: %s, %zu points, %zu sampled targets\n", argv[3], set.c_str(), n, s.size());
  return 0;
}
