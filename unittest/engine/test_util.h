// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Shared helpers of the engine tests: point distributions and error norms.
#pragma once

#include "kifmm.h"

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

namespace kifmm_test {

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

// Options of a periodic evaluation: the cubic cell of half-width h centered at c (origin if
// null) as fixed root; grid: cells per side of the single-level grid (0: octree of this leaf).
inline kifmm::Options periodic_options(int order, int leaf, double h = 1.0, const double c[3] = nullptr, int grid = 0)
{
  kifmm::Options o;
  o.order = order;
  o.leaf_size = leaf;
  o.fixed_root = true;
  o.periodic = true;
  o.periodic_grid = grid;
  o.root_half_width = h;
  if (c)
    for (int d = 0; d < 3; ++d) o.root_center[d] = c[d];
  return o;
}

// The same points with the mean charge subtracted (net charge zero).
inline Points neutral(Points p)
{
  double s = 0;
  for (double q : p.q) s += q;
  for (double &q : p.q) q -= s / p.q.size();
  return p;
}

inline double rel_l2(const std::vector<double> &a, const std::vector<double> &ref)
{
  double num = 0, den = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    num += (a[i] - ref[i]) * (a[i] - ref[i]);
    den += ref[i] * ref[i];
  }
  return den > 0 ? std::sqrt(num / den) : std::sqrt(num);
}

struct Errors {
  double pot = 0, grad = 0;
};

// Direct-sum reference values for a source/target configuration.
struct Reference {
  std::vector<double> pot, grad;
};
inline Reference reference(const kifmm::KernelSpec &k, const Points &src, const Points &t)
{
  Reference r;
  r.pot.resize(t.size());
  r.grad.resize(3 * t.size());
  kifmm::direct_sum(k, src.size(), src.xyz.data(), src.q.data(), t.size(), t.xyz.data(), r.pot.data(), r.grad.data());
  return r;
}
inline Errors fmm_errors(kifmm::Evaluator &ev, const Points &src, const Points &t, const Reference &ref)
{
  const std::size_t nt = t.size();
  std::vector<double> p(nt), g(3 * nt);
  ev.evaluate(src.size(), src.xyz.data(), src.q.data(), nt, t.xyz.data(), p.data(), g.data());
  return Errors{rel_l2(p, ref.pot), rel_l2(g, ref.grad)};
}

// FMM vs direct sum (targets = sources unless given).
inline Errors fmm_errors(kifmm::Evaluator &ev, const Points &src, const Points *trg = nullptr)
{
  const Points &t = trg ? *trg : src;
  const std::size_t nt = t.size();
  std::vector<double> p(nt), g(3 * nt), pr(nt), gr(3 * nt);
  ev.evaluate(src.size(), src.xyz.data(), src.q.data(), nt, t.xyz.data(), p.data(), g.data());
  kifmm::direct_sum(ev.kernel(), src.size(), src.xyz.data(), src.q.data(), nt, t.xyz.data(), pr.data(), gr.data());
  return Errors{rel_l2(p, pr), rel_l2(g, gr)};
}

inline Errors fmm_errors(const kifmm::KernelSpec &k, int order, int leaf, const Points &src,
                         const Points *trg = nullptr)
{
  kifmm::Options o;
  o.order = order;
  o.leaf_size = leaf;
  auto ev = kifmm::make_evaluator(k, o);
  return fmm_errors(*ev, src, trg);
}

}    // namespace kifmm_test
