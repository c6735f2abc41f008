// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Declaration of the data members of LAMMPS's FixRigidSmall, as laid out in LAMMPS 29 Sep 2021
// (Debian's liblammps-dev, which does not ship fix_rigid_small.h), for fix clump/rigid built
// against Debian's LAMMPS (a source tree's own RIGID/fix_rigid_small.h is used otherwise; both
// through compat/lammps_api.h).
//
// Why: rigid/small of this version keeps its bodies out of binary restart files; it writes a
// side file (<restart>.rigid, its *infile* format) from which a restarted run re-derives the
// principal axes (Jacobi diagonalization), the orientation quaternion and the body-frame
// pebble offsets. Those differ from the integrated ones in the last bits, so a run split by
// a restart drifts away from the unsplit run. fix clump/rigid stores the exact body state
// (mass, centre of mass, velocity, quaternion, principal moments and axes, angular momentum
// and velocity, image flags) and the body-frame offset of every pebble in the restart file and
// puts them back into rigid/small after its set-up in the restarted run.
//
// Only data members are declared (the class is never constructed, copied or sized here;
// data members of a class derived from Fix start at the same offset whatever its virtual
// functions). RigidSmallAccess::check (compat/lammps_api.cpp) checks the layout before fix
// clump/rigid reads or writes anything through it (rank and size, the infile name it gave, the
// largest body ID, the atom-to-body array and the body mass vector that FixRigidSmall::extract()
// returns, sizeof(Body)); the fix falls back to the documented infile route with a warning if
// the check fails.
#pragma once

#include "fix.h"
#include "lmptype.h"

namespace LAMMPS_NS {

class RigidSmallLayout : public Fix {
 public:
  int me, nprocs;
  double dtv, dtf, dtq;
  double *step_respa;
  int triclinic;

  char *inpfile;
  int setupflag;
  int earlyflag;
  int commflag;
  int customflag;
  int nbody;
  int nlinear;
  tagint maxmol;
  double maxextent;

  struct Body {
    double mass;
    double xcm[3];
    double vcm[3];
    double fcm[3];
    double torque[3];
    double quat[4];
    double inertia[3];
    double ex_space[3];
    double ey_space[3];
    double ez_space[3];
    double angmom[3];
    double omega[3];
    double conjqm[4];
    imageint image;
    int remapflag[4];
    int ilocal;
  };

  Body *body;
  int nlocal_body;
  int nghost_body;
  int nmax_body;
  int bodysize;

  int *bodyown;
  tagint *bodytag;
  int *atom2body;
  imageint *xcmimage;
  double **displace;
  int *eflags;
  double **orient;
  double **dorient;

  int extended;
  int orientflag;
  int dorientflag;
  int reinitflag;

  class AtomVecEllipsoid *avec_ellipsoid;
  class AtomVecLine *avec_line;
  class AtomVecTri *avec_tri;

  int **counts;
  double **itensor;

  double *mass_body;
  int nmax_mass;

  RigidSmallLayout() = delete;
  RigidSmallLayout(const RigidSmallLayout &) = delete;
  RigidSmallLayout &operator=(const RigidSmallLayout &) = delete;
};

}    // namespace LAMMPS_NS
