// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point sets of the engine tests and the benchmarks (one definition for both; CMake target
// kifmm_point_sets): uniform cube, Plummer sphere, clusters, a plane, close dipoles.
#pragma once

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

namespace kifmm_points {

struct Points {
  std::vector<double> xyz, q;
  std::size_t size() const { return q.size(); }
};

inline Points uniform_cube(std::size_t n, unsigned seed, double half = 1.0)
{
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(-half, half), uq(-1.0, 1.0);
  Points p;
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) p.xyz.push_back(u(g));
    p.q.push_back(uq(g));
  }
  return p;
}

// Plummer sphere (scale radius 1), radius clipped at 50, equal masses.
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
    p.xyz.push_back(r * s * std::cos(ph));
    p.xyz.push_back(r * s * std::sin(ph));
    p.xyz.push_back(r * z);
    p.q.push_back(1.0 / n);
  }
  return p;
}

// Two dense Gaussian clusters (sigma 1e-3) 10 apart.
inline Points two_clusters(std::size_t n, unsigned seed)
{
  std::mt19937_64 g(seed);
  std::normal_distribution<double> nd(0.0, 1e-3);
  std::uniform_real_distribution<double> uq(-1.0, 1.0);
  Points p;
  for (std::size_t i = 0; i < n; ++i) {
    const double cx = (i % 2) ? 5.0 : -5.0;
    p.xyz.push_back(cx + nd(g));
    p.xyz.push_back(nd(g));
    p.xyz.push_back(nd(g));
    p.q.push_back(uq(g));
  }
  return p;
}

// Points on the plane z = 0.3.
inline Points plane(std::size_t n, unsigned seed)
{
  Points p = uniform_cube(n, seed);
  for (std::size_t i = 0; i < n; ++i) p.xyz[3 * i + 2] = 0.3;
  return p;
}

// Neutral pairs +q/-q at distance 1e-3.
inline Points dipoles(std::size_t npairs, unsigned seed)
{
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points p;
  for (std::size_t i = 0; i < npairs; ++i) {
    double c[3], d[3], nrm = 0;
    for (int k = 0; k < 3; ++k) {
      c[k] = u(g);
      d[k] = u(g);
      nrm += d[k] * d[k];
    }
    nrm = std::sqrt(nrm);
    for (int s = -1; s <= 1; s += 2) {
      for (int k = 0; k < 3; ++k) p.xyz.push_back(c[k] + s * 0.5e-3 * d[k] / nrm);
      p.q.push_back(s * 1.0);
    }
  }
  return p;
}

// n alternating charges +-1 in a Gaussian cluster of this width around (c, c, c)
inline Points gaussian_cluster(std::size_t n, double c, double sigma, unsigned seed)
{
  Points p;
  std::mt19937_64 g(seed);
  std::normal_distribution<double> nd(0.0, sigma);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) p.xyz.push_back(c + nd(g));
    p.q.push_back(i % 2 ? 1.0 : -1.0);
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

// The same points with the mean charge subtracted (net charge zero).
inline Points neutral(Points p)
{
  double s = 0;
  for (double q : p.q) s += q;
  for (double &q : p.q) q -= s / p.q.size();
  return p;
}

}    // namespace kifmm_points
