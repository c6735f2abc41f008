// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Declaration of the leading data members of LAMMPS's FixEfield, as laid out in LAMMPS 29 Sep
// 2021 (Debian's liblammps-dev, which does not ship fix_efield.h), for fix kifmm/polarize built
// against Debian's LAMMPS (a source tree's own fix_efield.h is used otherwise; both through
// compat/lammps_api.h). fix kifmm/polarize reads the constant field a fix efield applies, the
// external field its induced dipoles respond to.
//
// Only data members are declared (the class is never constructed, copied or sized here). The
// layout is checked before the field is read (efield_constant_field, compat/lammps_api.cpp):
// the stored qe2f equals force->qe2f, and the field is constant everywhere (no variable names,
// no region: null pointers, region index -1).
#pragma once

#include "fix.h"

namespace LAMMPS_NS {

class EfieldLayout : public Fix {
 public:
  double ex, ey, ez;    // the field times qe2f (force / charge)
  int varflag, iregion;
  char *xstr, *ystr, *zstr, *estr;
  char *idregion;
  int xvar, yvar, zvar, evar, xstyle, ystyle, zstyle, estyle;
  int ilevel_respa;
  double qe2f;
};

}    // namespace LAMMPS_NS
