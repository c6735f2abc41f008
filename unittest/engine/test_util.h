// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Shared helpers of the engine tests: error norms, periodic options; the point sets are those of
// kifmm_point_sets.h (shared with the benchmarks).
#pragma once

#include "kifmm.h"
#include "kifmm_point_sets.h"

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

namespace kifmm_test {

using kifmm_points::Points;
using kifmm_points::uniform_cube;
using kifmm_points::plummer;
using kifmm_points::two_clusters;
using kifmm_points::plane;
using kifmm_points::dipoles;
using kifmm_points::gaussian_cluster;
using kifmm_points::neutral;
using kifmm_points::plummer_box;

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
