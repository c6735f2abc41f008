// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
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
//   - restart files: the exact state of every clump (mass properties, position, orientation,
//     motion) and the body-frame offset of every pebble, put back into rigid/small after its
//     set-up in the restarted run (a run split by a restart equals the unsplit run);
//     write_data keeps the pebbles and molecule IDs only (a warning says so);
//   - the pebble count of every clump, checked at each run (pebbles deleted or added after the
//     mass properties were computed are an error);
//   - for kspace_style kifmm (KIFMMRigidBodies, fix_clump_rigid_bodies.cpp): the pair sums
//     inside each clump in the body frame, so that the kspace leaves them out.
#pragma once

#include "fix.h"
#include "kifmm_rigid_bodies.h"

#include <array>
#include <map>
#include <string>
#include <vector>

namespace kifmm_lammps {
class RigidSmallAccess;
}

namespace LAMMPS_NS {

class FixClumpRigid : public Fix, public KIFMMRigidBodies {
 public:
  FixClumpRigid(class LAMMPS *, int, char **);
  ~FixClumpRigid() override;
  int setmask() override;
  void post_constructor() override;
  void init() override;
  double compute_vector(int) override;
  void *extract(const char *, int &) override;
  void set_molecule(int, tagint, int, double *, double *, double *) override;
  void setup_post_neighbor() override;
  void setup(int) override;
  void initial_integrate(int) override;

  // restart files: global settings, per-atom body-frame offsets and (on the atom that owns
  // its clump in rigid/small) the clump state
  void write_restart(FILE *) override;
  void restart(char *) override;
  int pack_restart(int, double *) override;
  void unpack_restart(int, int) override;
  int size_restart(int) override;
  int maxsize_restart() override;
  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;
  double memory_usage() override;

  // ---- KIFMMRigidBodies (fix_clump_rigid_bodies.cpp)
  const char *bodies_id() const override { return id; }
  bool bodies_ready(std::string &why) override;
  void compute_body_values(const Strength &strength, const BodyFunction &f) override;
  const double *body_values(int i) const override;
  void body_frame(int i, double rotation[9], double offset[3]) const override;
  tagint body_tag(int i) const override;

  // write_data: a comment in the data file and a warning (no clump state in data files)
  void write_data_section_size(int, int &, int &) override;
  void write_data_section_pack(int, double **) override;
  void write_data_section_keyword(int, FILE *) override;
  void write_data_section(int, FILE *, int, double **, int) override;

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
  std::string bodies_file;    // infile written for rigid/small, rank 0

  // ---- restart
  // clump record: mol, mass, xcm[3], vcm[3], quat[4], inertia[3], ex[3], ey[3], ez[3],
  // angmom[3], omega[3], conjqm[4], image
  static constexpr int NREC = 35;
  double **rdisp = nullptr;          // per atom: restored body-frame offset [0..2], valid [3]
  std::vector<double> rrecords;      // clump records unpacked on this rank
  std::map<tagint, std::vector<double>> restored;    // all clump records (every rank)
  bool restart_has_state = false;    // the restart file holds the clump state
  double restart_density = 0.0;      // density of the run that wrote it (0: infile)
  bool restore_pending = false;      // put the state back at the next setup
  bool write_exact = false;          // the restart being written has the clump state
  bool restart_warned = false;
  // rigid/nve/small recomputes its conjugate quaternion momenta from the angular momenta at
  // every run set-up (a roundoff-level change); they are kept across runs and restarts
  bool conjqm_valid = false;
  std::vector<std::array<double, 4>> conjqm_hold;
  // the gravity keyword's force on the clumps must be in the body forces of the first
  // half-step of a run; rigid/small's setup() leaves it out in some LAMMPS versions (then it is
  // added before the first step). Which: the body forces rigid/small set up are compared with
  // the pebble forces it set them up from (grav_fsum, summed in setup() when rigid/small's
  // setup() comes right after it: grav_measured).
  std::string grav_id;
  bool gravity_pending = false;
  bool grav_measured = false;
  double grav_fsum[3] = {0.0, 0.0, 0.0};

  // ---- per pebble: pair sums inside its clump (KIFMMRigidBodies::nvalues), the strength they
  // were computed with, valid flag, pebble count of its clump when first checked (0: not yet)
  enum { BV_STRENGTH = value_strength, BV_VALID = value_valid, BV_COUNT = value_count, NBV };
  double **bodyval = nullptr;
  bool counts_checked = false;       // pebble counts checked in this run
  Fix *bodies_rigid = nullptr;    // the rigid fix, when bodies_ready() found its bodies usable
  void gather_clumps(const Strength *strength, const BodyFunction *f);
  static int clump_callback(int n, char *inbuf, int &flag, int *&proclist, char *&outbuf, void *ptr);
  const BodyFunction *rendezvous_function = nullptr;

  Fix *rigid_fix();
  // rigid/small's bodies, checked (empty, and why, when they cannot be used)
  kifmm_lammps::RigidSmallAccess rigid_layout(std::string &why);
  void setup_templates();
  void write_bodies_file();
  void write_restored_bodies_file();
  void copy_user_infile();
  void restore_state();
};

}    // namespace LAMMPS_NS
