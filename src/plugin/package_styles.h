// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The styles of the lammps-kifmm package, in LAMMPS plugin form: one table shared by
// kifmmplugin.so (lammpsplugin_init), lmp_kifmm (built-in styles) and the Python entry point.
#pragma once

#include "lammpsplugin.h"

#include <vector>

namespace LAMMPS_NS {
class LAMMPS;
}

namespace kifmm_lammps {

// Version of LAMMPS the package is built against (the plugin ABI compares it).
extern const char *const lammps_version_built_against;

const std::vector<lammpsplugin_t> &package_styles();

// Puts every package style into the style maps of `lmp`; returns how many.
int add_package_styles(LAMMPS_NS::LAMMPS *lmp);

}    // namespace kifmm_lammps
