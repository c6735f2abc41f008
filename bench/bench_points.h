// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point sets shared by the benchmark programs.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace bench {

struct Points {
  std::vector<double> xyz, q;
  std::size_t size() const { return q.size(); }
};

inline Points uniform(std::size_t n, unsigned seed)
{
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points p;
  p.xyz.resize(3 * n);
  p.q.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] = u(g);
    p.q[i] = u(g);
  }
  return p;
}

inline Points plummer(std::size_t n, unsigned seed)
{
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Points p;
  while (p.size() < n) {
    const double m = u(g);
    const double r = 1.0 / std::sqrt(std::pow(m, -2.0 / 3.0) - 1.0);
    if (!(r < 50.0)) continue;
    const double z = 2 * u(g) - 1, ph = 2 * M_PI * u(g), s = std::sqrt(1 - z * z);
    p.xyz.insert(p.xyz.end(), {r * s * std::cos(ph), r * s * std::sin(ph), r * z});
    p.q.push_back(1.0 / n);
  }
  return p;
}

// Plummer sphere of scale a in the unit cube (centre 0.5, radii cut at 0.45), charges +-1
// alternating (as the bench/solvers "plummer" configuration, unittest/fixture/configurations.cpp)
inline Points plummer_box(std::size_t n, unsigned seed, double a)
{
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Points p;
  while (p.size() < n) {
    const double m = u(g);
    if (m < 1e-10 || m > 1 - 1e-10) continue;
    const double r = a / std::sqrt(std::pow(m, -2.0 / 3.0) - 1.0);
    if (r > 0.45) continue;
    const double z = 2 * u(g) - 1, ph = 2 * M_PI * u(g), s = std::sqrt(1 - z * z);
    p.xyz.insert(p.xyz.end(), {0.5 + r * s * std::cos(ph), 0.5 + r * s * std::sin(ph), 0.5 + r * z});
    p.q.push_back(p.size() % 2 ? -1.0 : 1.0);
  }
  return p;
}

// Named point sets: uniform points (seed 1) of each size, then Plummer spheres (seed 2) of each
// size, as the engine benchmarks sweep them
struct NamedPoints {
  std::string name;
  Points pts;
};

inline std::vector<NamedPoints> uniform_and_plummer(const std::vector<double> &sizes,
                                                    const std::vector<double> &plummer_sizes)
{
  std::vector<NamedPoints> sets;
  for (double n : sizes) sets.push_back({"uniform", uniform((std::size_t) n, 1)});
  for (double n : plummer_sizes) sets.push_back({"plummer", plummer((std::size_t) n, 2)});
  return sets;
}

// Relative RMS error of grad (3 per target, all targets) at the targets sample[i] against
// ref (3 per sampled target, in the order of sample)
inline double sampled_relative_rms(const std::vector<double> &grad,
                                   const std::vector<std::size_t> &sample,
                                   const std::vector<double> &ref)
{
  double num = 0, den = 0;
  for (std::size_t i = 0; i < sample.size(); ++i)
    for (int d = 0; d < 3; ++d) {
      const double a = grad[3 * sample[i] + d], b = ref[3 * i + d];
      num += (a - b) * (a - b);
      den += b * b;
    }
  return std::sqrt(num / den);
}

}    // namespace bench
