// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The settings of kspace_style kifmm and the parser of its `kspace_modify kifmm ...` keywords.
// Pure C++ (no LAMMPS), so that it is unit-tested and fuzzed on its own; the kspace style turns
// a parse error into a LAMMPS error naming the bad token.
#pragma once

#include <string>
#include <vector>

namespace kifmm_lammps {

enum class LongRangeKernel { Coulomb, Gravity, Yukawa };

struct KIFMMSettings {
  double accuracy = 1e-5;    // relative RMS force error wanted (kspace_style argument)
  LongRangeKernel kernel = LongRangeKernel::Coulomb;
  double gravity_G = 1.0;    // gravity: F = G m_i m_j / r^2, attractive
  double kappa = 0.0;        // yukawa: qqrd2e q_i q_j exp(-kappa r) / r
  int order = 0;             // 0 = from accuracy (calibration); else points per surface edge
  int leaf = 0;              // 0 = from calibration; else max points per leaf
  // periodic, one rank: -1 = auto (the single-level grid when the cost model prefers it to the
  // octree), 0 = no (octree), k = grid of k^3 cells (kifmm::Options::periodic_grid)
  int grid = -1;
  bool tune = true;          // tree (leaf size or grid) not given: time the trees near the modelled
                             // choice on the first evaluations of a run (kifmm::TreeTuner)
  int check_every = 0;       // 0 = off; else measure the error every N steps
  int check_samples = 0;
  std::string cache_dir;     // "" = default location; "none" = in-memory only
  bool jeans = false;        // gravity + periodic boundaries: uniform negative background
};

constexpr int kifmm_min_order = 2;
constexpr int kifmm_max_order = 16;
constexpr int kifmm_min_grid = 3;
constexpr int kifmm_max_grid = 32;

// Parses the accuracy argument of `kspace_style kifmm ACCURACY`; returns "" or an error text.
std::string parse_accuracy(const std::string &token, KIFMMSettings &settings);

// Parses the keywords that follow `kifmm` in `kspace_modify kifmm ...`. Stops at the first
// token that is not a kifmm keyword (so LAMMPS's generic kspace_modify keywords may follow)
// and sets `consumed` to the number of tokens used (including "kifmm"). Returns "" or an
// error text naming the bad token.
std::string parse_kifmm_keywords(const std::vector<std::string> &args, KIFMMSettings &settings,
                                 int &consumed);

const char *kernel_name(LongRangeKernel kernel);

}    // namespace kifmm_lammps
