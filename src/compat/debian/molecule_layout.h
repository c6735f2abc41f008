// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Declaration of the data members of LAMMPS's Molecule class (a molecule template), as laid
// out in LAMMPS 29 Sep 2021 (Debian's liblammps-dev, which does not ship molecule.h), for fix
// clump/rigid built against Debian's LAMMPS (a source tree's own molecule.h is used otherwise;
// both through compat/lammps_api.h).
//
// Why: fix pour and fix deposit give inserted rigid bodies the mass, centre of mass and
// inertia of the molecule template (FixRigidSmall::set_molecule reads masstotal, com, itensor
// of the template). For clumps these must be the union-of-spheres values, so fix clump/rigid
// reads the pebbles of the template (x, radius) and stores the union mass properties in it
// (masstotal, com, itensor + their flags), as the `mass`, `com` and `inertia` header keywords
// of a molecule file would. LAMMPS offers no accessor for these members, and no header.
//
// Only the leading, public data members are declared (the class is never constructed, copied,
// or sized here), plus the exported member functions the fix calls. molecule_members_ok
// (compat/lammps_api.cpp) checks the layout at run time before the fix writes anything
// (template ID, flags in {0,1}, and compute_center() writing the mean of x into `center`); the
// fix stops with an error if it does not match.
#pragma once

#include "lmptype.h"
#include "pointers.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {

class Molecule : protected Pointers {
 public:
  char *id;
  int nset;
  int last;

  int natoms;
  int nbonds, nangles, ndihedrals, nimpropers;
  int ntypes, nmolecules, nfragments;
  int nbondtypes, nangletypes, ndihedraltypes, nimpropertypes;
  int nibody, ndbody;

  int bond_per_atom, angle_per_atom, dihedral_per_atom, improper_per_atom;
  int maxspecial;

  int xflag, typeflag, moleculeflag, fragmentflag, qflag, radiusflag, rmassflag;
  int bondflag, angleflag, dihedralflag, improperflag;
  int nspecialflag, specialflag;
  int shakeflag, shakeflagflag, shakeatomflag, shaketypeflag;
  int bodyflag, ibodyflag, dbodyflag;

  int centerflag, massflag, comflag, inertiaflag;

  int tag_require;

  double **x;
  int *type;
  tagint *molecule;
  double *q;
  double *radius;
  double *rmass;

  int *num_bond;
  int **bond_type;
  tagint **bond_atom;

  int *num_angle;
  int **angle_type;
  tagint **angle_atom1, **angle_atom2, **angle_atom3;

  int *num_dihedral;
  int **dihedral_type;
  tagint **dihedral_atom1, **dihedral_atom2, **dihedral_atom3, **dihedral_atom4;

  int *num_improper;
  int **improper_type;
  tagint **improper_atom1, **improper_atom2, **improper_atom3, **improper_atom4;

  int **nspecial;
  tagint **special;

  int *shake_flag;
  tagint **shake_atom;
  int **shake_type;

  class AtomVecBody *avec_body;
  int *ibodyparams;
  double *dbodyparams;

  int **fragmentmask;
  std::vector<std::string> fragmentnames;

  double center[3];
  double masstotal;
  double com[3];
  double itensor[6];
  double inertia[3];
  double ex[3], ey[3], ez[3];
  double quat[4];

  double maxradius;
  double molradius;
  int comatom;
  double maxextent;

  // exported by liblammps
  void compute_center();
  void compute_mass();
  void compute_com();
  void compute_inertia();

  Molecule() = delete;
  Molecule(const Molecule &) = delete;
  Molecule &operator=(const Molecule &) = delete;
};

}    // namespace LAMMPS_NS
