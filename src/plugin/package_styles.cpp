#include "package_styles.h"

#include "style_maps.h"

#include "lammps.h"

using namespace LAMMPS_NS;

namespace kifmm_lammps {

const char *const lammps_version_built_against = KIFMM_LAMMPS_VERSION;

const std::vector<lammpsplugin_t> &package_styles()
{
  // Styles are added here as they are implemented (kspace kifmm, fix kifmm/stride,
  // fix clump/rigid); see src/KIFMM and src/RIGID_CLUMP.
  static const std::vector<lammpsplugin_t> styles = {};
  return styles;
}

int add_package_styles(LAMMPS *lmp)
{
  int n = 0;
  for (const auto &style : package_styles())
    if (add_style_to_maps(lmp, style, false)) ++n;
  return n;
}

}    // namespace kifmm_lammps
