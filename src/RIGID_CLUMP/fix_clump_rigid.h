// fix clump/rigid: rigid clumps of (charged) spherical pebbles. See doc/fix_clump_rigid.rst.
//
// Composition, not a new integrator: the fix owns an internal `rigid/small` (or
// `rigid/nve/small`) fix, ID "<ID>_rigid", which integrates the clumps (one clump = one
// molecule ID) and which fix pour/deposit and the granular pair/wall styles use. This fix adds:
//   - union-of-spheres mass, centre of mass and inertia at a user density (or explicit ones),
//     fed to rigid/small through its infile for existing clumps and stored in the molecule
//     template for clumps inserted by fix pour / fix deposit;
//   - the initial clump velocities and angular momenta, fitted to the pebble velocities;
//   - intra-clump contact exclusion (neigh_modify exclude molecule/intra group-ID);
//   - outputs: number of clumps, translational and rotational kinetic energy (global
//     vector), and the per-clump compute rigid/local "<ID>_local" (orientation quaternion,
//     position, angular momentum, ...) for dump local.
#pragma once

#include "fix.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {

class FixClumpRigid : public Fix {
 public:
  FixClumpRigid(class LAMMPS *, int, char **);
  ~FixClumpRigid() override;
  int setmask() override;
  void post_constructor() override;
  void init() override;
  double compute_vector(int) override;
  void *extract(const char *, int &) override;
  void set_molecule(int, tagint, int, double *, double *, double *) override;

 private:
  double density = 0.0;     // > 0: union mass properties at this density
  std::string user_infile;  // explicit mass properties (rigid/small infile format)
  std::string template_id;  // molecule template for fix pour / fix deposit
  std::string integrator = "rigid/small";
  std::string extra_args;   // langevin / gravity keywords passed to rigid/small
  double tol = 1e-5;        // relative accuracy of the union integration
  int exclude = 1;
  tagint maxmol = 0;         // largest clump (molecule) ID when the fix was defined

  std::string id_rigid, id_ke, id_erot, id_local;
  std::string bodies_file;    // infile written for rigid/small (density mode), rank 0

  Fix *rigid_fix();
  void setup_templates();
  void write_bodies_file();
};

}    // namespace LAMMPS_NS
