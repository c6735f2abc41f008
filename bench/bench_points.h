// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point sets of the benchmark programs (kifmm_point_sets.h, shared with the engine tests).
#pragma once

#include "kifmm_point_sets.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace bench {

using kifmm_points::Points;
using kifmm_points::plummer;
using kifmm_points::plummer_box;
inline Points uniform(std::size_t n, unsigned seed) { return kifmm_points::uniform_cube(n, seed); }

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

// The atoms of nonzero charge of the "Atoms # charge" section of a LAMMPS data file
// (id type q x y z)
inline Points read_charge_data(const std::string &path)
{
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::string line;
  bool atoms = false;
  Points p;
  while (std::getline(in, line)) {
    if (line.rfind("Atoms", 0) == 0) {
      atoms = true;
      continue;
    }
    if (!atoms) continue;
    std::istringstream ls(line);
    long id;
    int type;
    double q, x, y, z;
    if (!(ls >> id >> type >> q >> x >> y >> z)) {
      if (!p.q.empty() && line.find_first_not_of(" \t\r") != std::string::npos) break;    // next section
      continue;
    }
    if (q == 0.0) continue;
    p.xyz.insert(p.xyz.end(), {x, y, z});
    p.q.push_back(q);
  }
  return p;
}


// The comma-separated items of a command-line value (empty items skipped), and as numbers
// (an item "a-b" of two integers: a, a + 1, .., b).
inline std::vector<std::string> split_list(const std::string &s)
{
  std::vector<std::string> v;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ','))
    if (!tok.empty()) v.push_back(tok);
  return v;
}
inline std::vector<double> number_list(const std::string &s)
{
  std::vector<double> v;
  for (const std::string &t : split_list(s)) {
    const std::size_t dash = t.find('-');
    if (dash != std::string::npos && dash > 0 && t.find_first_not_of("0123456789-") == std::string::npos) {
      // a range of integers, "3-14"
      for (int k = std::atoi(t.c_str()); k <= std::atoi(t.c_str() + dash + 1); ++k) v.push_back(k);
    } else {
      v.push_back(std::atof(t.c_str()));
    }
  }
  return v;
}

// ||a - ref|| / ||ref|| over all entries
inline double relative_difference(const std::vector<double> &a, const std::vector<double> &ref)
{
  double num = 0, den = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    num += (a[i] - ref[i]) * (a[i] - ref[i]);
    den += ref[i] * ref[i];
  }
  return std::sqrt(num / den);
}

// The bounding box of the points.
inline void bounding_box(const Points &p, double lo[3], double hi[3])
{
  for (int d = 0; d < 3; ++d) lo[d] = 1e300, hi[d] = -1e300;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p.xyz[3 * i + d]);
      hi[d] = std::max(hi[d], p.xyz[3 * i + d]);
    }
}

// The points scaled into the periodic cell [-1,1]^3 (a small margin inside), charges shifted to
// a zero sum.
inline Points into_periodic_cell(Points p)
{
  double lo[3], hi[3];
  bounding_box(p, lo, hi);
  const double w = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  double qsum = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int d = 0; d < 3; ++d)
      p.xyz[3 * i + d] = -0.999 + 1.998 * (p.xyz[3 * i + d] - 0.5 * (lo[d] + hi[d]) + 0.5 * w) / w;
    qsum += p.q[i];
  }
  for (double &q : p.q) q -= qsum / p.size();
  return p;
}

}    // namespace bench
