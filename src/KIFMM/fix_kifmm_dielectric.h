// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix ID group kifmm/dielectric permittivity EPS field Ex Ey Ez [degree L] [tol T] [order P]
//                               [shrink S] [overlap touch|error] [every N]
//
// Dielectric spheres (the group; atom radii) in a uniform external field, polarized beyond the
// point-dipole model: the bound surface charge of every sphere from the boundary integral
// equation of the engine (kifmm::polarize_dielectric_spheres, GMRES with the FMM field of the
// surface nodes), its force and torque on each sphere at every step (post_force), the
// polarization energy -1/2 sum mu . E as the fix's scalar, the induced dipoles per atom; every
// N: solved on every N-th step, the forces held in between. Open boundaries. Every rank solves
// for all spheres of the group. See doc/fix_kifmm_dielectric.rst.
#pragma once

#include "fix.h"

#include <memory>
#include <vector>

namespace kifmm {
class Evaluator;
}

namespace LAMMPS_NS {

class FixKIFMMDielectric : public Fix {
 public:
  FixKIFMMDielectric(class LAMMPS *, int, char **);
  ~FixKIFMMDielectric() override;
  int setmask() override;
  void init() override;
  void setup(int) override;
  void min_setup(int) override;
  void post_force(int) override;
  void min_post_force(int) override;
  double compute_scalar() override;
  double compute_vector(int) override;
  double memory_usage() override;

 private:
  double permittivity = 0, field[3] = {0, 0, 0}, tol = 1e-6, shrink = 0;
  int degree = 12, order = 8;
  std::unique_ptr<kifmm::Evaluator> evaluator;
  double energy = 0, residual = 0;
  int iterations = 0, nmax = 0;
  double near_rows = 0, overlapping_pairs = 0;
  bool touch_overlaps = true;
  double **dipole = nullptr;    // induced dipole of each local atom (array_atom)
  int every = 1;
  bigint last_solve = -1;
  // the last solve: atom IDs (sorted), forces, torques, dipoles (3 each) in LAMMPS units
  std::vector<tagint> ids;
  std::vector<double> sphere_force, sphere_torque, sphere_dipole;
  void solve();
  void apply();
};

}    // namespace LAMMPS_NS
