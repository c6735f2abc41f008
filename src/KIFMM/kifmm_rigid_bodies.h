// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Rigid bodies whose internal pairs kspace_style kifmm leaves out of the long-range sum.
//
// The pebbles of one rigid clump keep their distances: the forces between them cancel in the
// clump's net force and torque, their energy is a constant, and in the body frame each pebble's
// share of them is a constant vector. A fix that owns rigid bodies (fix clump/rigid) implements
// this interface; the kspace style finds it among the fixes, has the per-pebble values computed
// once per body (compute_body_values, with the kernel's pair sum inside each body) and, at
// every evaluation, subtracts them rotated into the lab frame. No O(N^2) work per evaluation.
#pragma once

#include "lmptype.h"
#include "pointers.h"

#include <functional>
#include <string>
#include <type_traits>

namespace LAMMPS_NS {

class KIFMMRigidBodies {
 public:
  // values kept per pebble: the body-frame pair sum inside its body (gradient 3, potential 1,
  // pair virial 6: see kifmm::group_pair_sum)
  static constexpr int nvalues = 10;
  // one body: n pebbles with body-frame offsets d (3n) and strengths s (n); fills out (10 n)
  using BodyFunction = std::function<void(int n, const double *d, const double *s, double *out)>;
  // strength (charge or mass) of a local atom
  using Strength = std::function<double(int i)>;

  // as LAMMPS's Pointers (noexcept(false) where LAMMPS errors may throw from destructors): the
  // fix implementing this interface is also a Fix
  virtual ~KIFMMRigidBodies() noexcept(std::is_nothrow_destructible_v<Pointers>) {}

  // ID of the fix (for messages)
  virtual const char *bodies_id() const = 0;
  // Collective. True when the bodies are set up and their geometry can be read (else `why`).
  virtual bool bodies_ready(std::string &why) = 0;
  // Collective: the per-pebble values of every body from its current pebbles and strengths
  // (pebbles are gathered per body across ranks). Stops with an error naming the clump when a
  // body no longer has the pebbles it was defined with.
  virtual void compute_body_values(const Strength &strength, const BodyFunction &f) = 0;
  // Local atom i: its values, or nullptr when i is not a pebble of a body. values[nvalues] is
  // the strength they were computed with, values[nvalues + 1] != 0 when they were computed
  // (in this run, since the atom exists), values[nvalues + 2] the pebble count of its body.
  enum { value_strength = nvalues, value_valid, value_count };
  virtual const double *body_values(int i) const = 0;
  // Local atom i of a body: rotation body frame -> lab frame (row-major 3x3, columns are the
  // body axes) and the lab-frame offset of i from its body's centre of mass.
  virtual void body_frame(int i, double rotation[9], double offset[3]) const = 0;
  // Local atom i: the ID of its body (clump = molecule ID), 0 when not in a body.
  virtual tagint body_tag(int i) const = 0;
};

}    // namespace LAMMPS_NS
