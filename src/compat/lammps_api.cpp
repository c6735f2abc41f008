// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "lammps_api.h"

#include "atom.h"
#include "comm.h"
#include "force.h"
#include "lammps.h"

#include <algorithm>
#include <cmath>
#include <cstring>

using namespace LAMMPS_NS;

namespace kifmm_lammps {

namespace {
#if KIFMM_LAMMPS_TREE
using M = detail::RigidSmallMembers;
const FixRigidSmall *rs(Fix *f)
{
  return static_cast<const FixRigidSmall *>(f);
}
#else
const RigidSmallLayout *rs(Fix *f)
{
  return reinterpret_cast<const RigidSmallLayout *>(f);
}
#endif
const char *const layout_mismatch =
    "the FixRigidSmall class of this LAMMPS does not match the one the package was built for";
}    // namespace

std::string RigidSmallAccess::check(LAMMPS *lmp, Fix *rigid, const std::string &infile,
                                    tagint maxmol)
{
#if KIFMM_LAMMPS_TREE
  (void) maxmol;
  // the fix is one of the rigid/small family (the cast below is then a real FixRigidSmall)
  if (strcmp(rigid->style, "rigid/small") != 0 && strcmp(rigid->style, "rigid/nve/small") != 0)
    return std::string("fix ") + rigid->id + " is a " + rigid->style + ", not a rigid/small fix";
  const FixRigidSmall *f = rs(rigid);
  if (M::get_bodysize(f) != (int) (sizeof(Body) / sizeof(double))) return layout_mismatch;
  const char *inpfile = M::get_inpfile(f);
  if (!inpfile || infile != inpfile || M::get_reinitflag(f) != 0) return layout_mismatch;
  const int setupflag = M::get_setupflag(f);
#else
  // the declared layout must hold values this fix knows: rank and size, the infile it gave,
  // the largest body ID when the fix was defined, flags in range, sizeof(Body)
  const RigidSmallLayout *v = rs(rigid);
  if (!(v->me == lmp->comm->me && v->nprocs == lmp->comm->nprocs && v->inpfile &&
        infile == v->inpfile && (v->maxmol == maxmol || (maxmol == 0 && v->maxmol == -1)) &&
        v->reinitflag == 0 && (v->setupflag == 0 || v->setupflag == 1) &&
        v->bodysize == (int) (sizeof(RigidSmallLayout::Body) / sizeof(double))))
    return layout_mismatch;
  const int setupflag = v->setupflag;
#endif
  if (!setupflag) return "its bodies are not set up";
  RigidSmallAccess a(rigid);
  int dim = 0;
  void *a2b = rigid->extract("body", dim);         // nullptr before the set-up
  void *mb = rigid->extract("masstotal", dim);     // owned+ghost body masses, refreshed
#if KIFMM_LAMMPS_TREE
  const double *mass_body = M::get_mass_body(rs(rigid));
  const int nmax_body = M::get_nmax_body(rs(rigid));
#else
  const double *mass_body = rs(rigid)->mass_body;
  const int nmax_body = rs(rigid)->nmax_body;
#endif
  const int nl = a.nlocal_body(), ng = a.nghost_body();
  bool ok = (void *) a.atom2body() == a2b && (const void *) mass_body == mb && nl >= 0 &&
      ng >= 0 && nl + ng <= nmax_body;
  const int nall = lmp->atom->nlocal + lmp->atom->nghost;
  for (int b = 0; b < nl + ng && ok; ++b)
    ok = a.body()[b].ilocal >= 0 && a.body()[b].ilocal < nall &&
        a.body()[b].mass == static_cast<const double *>(mb)[b];
  if (!ok) return layout_mismatch;
  return "";
}

#if KIFMM_LAMMPS_TREE
RigidSmallAccess::Body *RigidSmallAccess::body() const { return M::get_body(rs(fix)); }
int RigidSmallAccess::nlocal_body() const { return M::get_nlocal_body(rs(fix)); }
int RigidSmallAccess::nghost_body() const { return M::get_nghost_body(rs(fix)); }
int *RigidSmallAccess::atom2body() const { return M::get_atom2body(rs(fix)); }
int *RigidSmallAccess::bodyown() const { return M::get_bodyown(rs(fix)); }
double **RigidSmallAccess::displace() const { return M::get_displace(rs(fix)); }

bool RigidSmallAccess::langevin_force(double sum[3]) const
{
  sum[0] = sum[1] = sum[2] = 0.0;
  const FixRigidSmall *f = rs(fix);
  double **extra = M::get_langextra(f);
  if (!M::get_langflag(f) || !extra) return true;
  for (int b = 0; b < M::get_nlocal_body(f); ++b)
    for (int d = 0; d < 3; ++d) sum[d] += extra[b][d];
  return true;
}
#else
RigidSmallAccess::Body *RigidSmallAccess::body() const { return rs(fix)->body; }
int RigidSmallAccess::nlocal_body() const { return rs(fix)->nlocal_body; }
int RigidSmallAccess::nghost_body() const { return rs(fix)->nghost_body; }
int *RigidSmallAccess::atom2body() const { return rs(fix)->atom2body; }
int *RigidSmallAccess::bodyown() const { return rs(fix)->bodyown; }
double **RigidSmallAccess::displace() const { return rs(fix)->displace; }

bool RigidSmallAccess::langevin_force(double sum[3]) const
{
  sum[0] = sum[1] = sum[2] = 0.0;
  return false;
}
#endif

bool molecule_members_ok(Molecule **mols, int nmolecule_left, const std::string &id)
{
#if KIFMM_LAMMPS_TREE
  (void) mols;
  (void) nmolecule_left;
  (void) id;
  return true;
#else
  // the template ID and set size where declared, flags in {0, 1}, and compute_center()
  // (LAMMPS's own code) putting the mean of x into `center`
  if (strcmp(mols[0]->id, id.c_str()) != 0 || mols[0]->nset < 1 ||
      mols[0]->nset > nmolecule_left)
    return false;
  auto is01 = [](int f) { return f == 0 || f == 1; };
  for (int m = 0; m < mols[0]->nset; ++m) {
    Molecule *mol = mols[m];
    if (!(mol->natoms > 0 && is01(mol->xflag) && is01(mol->radiusflag) && is01(mol->massflag) &&
          is01(mol->comflag) && is01(mol->inertiaflag) && is01(mol->qflag)))
      return false;
    if (!mol->xflag) continue;
    mol->compute_center();
    double c[3] = {0, 0, 0}, ext = 0.0;
    for (int i = 0; i < mol->natoms; ++i)
      for (int d = 0; d < 3; ++d) c[d] += mol->x[i][d] / mol->natoms;
    for (int i = 0; i < mol->natoms; ++i)
      for (int d = 0; d < 3; ++d) ext = std::max(ext, std::fabs(mol->x[i][d] - c[d]));
    for (int d = 0; d < 3; ++d)
      if (std::fabs(c[d] - mol->center[d]) > 1e-9 * (ext + 1e-300) + 1e-300) return false;
  }
  return true;
#endif
}

std::string efield_constant_field(LAMMPS *lmp, Fix *efield, double e[3])
{
  e[0] = e[1] = e[2] = 0.0;
  if (strcmp(efield->style, "efield") != 0) return std::string("fix ") + efield->id + " is not a fix efield";
#if KIFMM_LAMMPS_TREE
  using E = detail::EfieldMembers;
  const auto *f = static_cast<const FixEfield *>(efield);
  if (E::get_qe2f(f) != lmp->force->qe2f)
    return "the FixEfield class of this LAMMPS does not match the one the package was built for";
  if (!E::get_constant(f)) return "its field is given by variables";
  if (E::get_region(f)) return "it acts in a region only";
  E::get_field(f, e);
#else
  const auto *f = reinterpret_cast<const EfieldLayout *>(efield);
  if (f->qe2f != lmp->force->qe2f)
    return "the FixEfield class of this LAMMPS does not match the one the package was built for";
  if (f->xstr || f->ystr || f->zstr) return "its field is given by variables";
  if (f->idregion || f->iregion != -1) return "it acts in a region only";
  e[0] = f->ex;
  e[1] = f->ey;
  e[2] = f->ez;
#endif
  return "";
}

}    // namespace kifmm_lammps
