// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Point sets of the benchmark programs (kifmm_point_sets.h, shared with the engine tests).
#pragma once

#include "kifmm_point_sets.h"

#include <cmath>
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

}    // namespace bench
