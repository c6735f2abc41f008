// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "package_styles.h"

#include "style_maps.h"

#include "fix_kifmm_dielectric.h"
#include "fix_kifmm_polarize.h"
#include "fix_kifmm_stride.h"
#include "fix_clump_rigid.h"
#include "kifmm_timing.h"
#include "kspace_kifmm.h"

#include "lammps.h"

using namespace LAMMPS_NS;

namespace kifmm_lammps {

const char *const lammps_version_built_against = KIFMM_LAMMPS_VERSION;

namespace {
void *make_fix_kifmm_timing(void *lmp, int narg, char **arg)
{
  return new FixKIFMMTiming(static_cast<LAMMPS *>(lmp), narg, arg);
}
void *make_kspace_kifmm(void *lmp)
{
  return new KSpaceKIFMM(static_cast<LAMMPS *>(lmp));
}
void *make_fix_kifmm_stride(void *lmp, int narg, char **arg)
{
  return new FixKIFMMStride(static_cast<LAMMPS *>(lmp), narg, arg);
}
void *make_fix_kifmm_polarize(void *lmp, int narg, char **arg)
{
  return new FixKIFMMPolarize(static_cast<LAMMPS *>(lmp), narg, arg);
}
void *make_fix_kifmm_dielectric(void *lmp, int narg, char **arg)
{
  return new FixKIFMMDielectric(static_cast<LAMMPS *>(lmp), narg, arg);
}
void *make_fix_clump_rigid(void *lmp, int narg, char **arg)
{
  return new FixClumpRigid(static_cast<LAMMPS *>(lmp), narg, arg);
}
}    // namespace

const std::vector<lammpsplugin_t> &package_styles()
{
  // The package's styles (kspace kifmm, fix kifmm/stride, fix kifmm/polarize, fix
  // kifmm/dielectric, fix clump/rigid);
  // see src/KIFMM and src/RIGID_CLUMP.
  static const std::vector<lammpsplugin_t> styles = [] {
    std::vector<lammpsplugin_t> v;
    auto add = [&](const char *kind, const char *name, const char *info) -> lammpsplugin_t & {
      lammpsplugin_t s{};
      s.version = lammps_version_built_against;
      s.style = kind;
      s.name = name;
      s.info = info;
      s.author = "lammps-kifmm developers";
      s.handle = nullptr;
      v.push_back(s);
      return v.back();
    };
    add("kspace", "kifmm", "long-range coulomb/gravity/yukawa by the kernel-independent FMM")
        .creator.v1 = &make_kspace_kifmm;
    add("fix", "KIFMM/TIMING", "internal: end-of-run time breakdown of kspace kifmm")
        .creator.v2 = &make_fix_kifmm_timing;
    add("fix", "kifmm/stride", "long-range forces of kspace kifmm refreshed every N steps")
        .creator.v2 = &make_fix_kifmm_stride;
    add("fix", "kifmm/polarize", "induced point dipoles of polarizable atoms, solved by kspace kifmm")
        .creator.v2 = &make_fix_kifmm_polarize;
    add("fix", "kifmm/dielectric", "dielectric spheres in a uniform field by a boundary integral equation")
        .creator.v2 = &make_fix_kifmm_dielectric;
    add("fix", "clump/rigid", "rigid clumps of spherical pebbles (union mass, wraps rigid/small)")
        .creator.v2 = &make_fix_clump_rigid;
    return v;
  }();
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
