// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Entry points of kifmmplugin.so.
//  - lammpsplugin_init: the standard LAMMPS plugin entry (`plugin load kifmmplugin.so` in a
//    plugin-enabled LAMMPS, or in lmp_kifmm).
//  - kifmm_register_styles: for Debian's python3-lammps (no `plugin` command there): takes the
//    LAMMPS handle (lammps.lmp in Python) and puts the package's styles into its style maps.
#include "package_styles.h"

#include "lammps.h"

extern "C" {

void lammpsplugin_init(void *lmp, void *handle, void *regfunc)
{
  auto reg = (lammpsplugin_regfunc) regfunc;
  for (lammpsplugin_t style : kifmm_lammps::package_styles()) {
    style.handle = handle;
    reg(&style, lmp);
  }
}

int kifmm_register_styles(void *lmp)
{
  return kifmm_lammps::add_package_styles(static_cast<LAMMPS_NS::LAMMPS *>(lmp));
}
}
