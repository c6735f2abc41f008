// Point sets shared by the benchmark programs.
#pragma once

#include <cmath>
#include <random>
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

}    // namespace bench
