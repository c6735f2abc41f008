// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The arguments of the near-field loops (p2p.h, p2p_dipole.h, p2p_mutual.h): points and the
// accumulators of their results, structure of arrays.
#pragma once

#include <cstddef>

namespace kifmm {

// Points of a near-field call: n points at x, y, z with strengths q (sources; targets leave q
// null) and, for dipole sources, dipole moments mx, my, mz (null: charges only).
struct PointSpan {
  std::size_t n = 0;
  const double *x = nullptr, *y = nullptr, *z = nullptr, *q = nullptr;
  const double *mx = nullptr, *my = nullptr, *mz = nullptr;
};

// Accumulators of the targets (results are ADDED): potential and gradient components, and
// the second derivatives of the potential (the field gradient; null: not computed). A
// component that is not computed may be null.
struct ResultSpan {
  double *pot = nullptr, *gx = nullptr, *gy = nullptr, *gz = nullptr;
  double *hxx = nullptr, *hyy = nullptr, *hzz = nullptr, *hxy = nullptr, *hxz = nullptr, *hyz = nullptr;
};

}    // namespace kifmm
