// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The parts of LAMMPS that the package reads beyond LAMMPS's public style interface, for both
// ways of building it:
//  - against a LAMMPS source tree (KIFMM_LAMMPS_TREE = 1, CMake option LAMMPS_SOURCE_DIR): the
//    tree's own headers, molecule.h and RIGID/fix_rigid_small.h;
//  - against Debian's liblammps-dev (KIFMM_LAMMPS_TREE = 0), which ships neither header: the
//    member declarations in compat/debian (molecule_layout.h, rigid_small_layout.h), checked at
//    run time before anything is read or written through them.
// KIFMM_LAMMPS_DATE is the version of those headers as YYYYMMDD (from the tree's version.h, or
// Debian's package version); every test of the LAMMPS version is in this header.
#pragma once

#if !defined(KIFMM_LAMMPS_DATE) || !defined(KIFMM_LAMMPS_TREE)
#error "KIFMM_LAMMPS_DATE and KIFMM_LAMMPS_TREE are set by the build (src/CMakeLists.txt)"
#endif

#include "fix.h"
#include "lmptype.h"

#if KIFMM_LAMMPS_TREE
#include "RIGID/fix_rigid_small.h"
#include "fix_efield.h"
#include "molecule.h"
#else
#include "efield_layout.h"
#include "molecule_layout.h"
#include "rigid_small_layout.h"
#endif

#include <string>

namespace LAMMPS_NS {
class LAMMPS;
}

namespace kifmm_lammps {

#if KIFMM_LAMMPS_TREE
namespace detail {
// FixRigidSmall keeps its bodies in protected members. A class derived from it may form
// pointers to those members (&RigidSmallMembers::body is a `Body *FixRigidSmall::*`), which
// then apply to any FixRigidSmall object. Never instantiated.
class RigidSmallMembers : public LAMMPS_NS::FixRigidSmall {
 public:
  using BodyType = LAMMPS_NS::FixRigidSmall::Body;
  using F = LAMMPS_NS::FixRigidSmall;
  static BodyType *get_body(const F *f) { return f->*(&RigidSmallMembers::body); }
  static int get_nlocal_body(const F *f) { return f->*(&RigidSmallMembers::nlocal_body); }
  static int get_nghost_body(const F *f) { return f->*(&RigidSmallMembers::nghost_body); }
  static int get_nmax_body(const F *f) { return f->*(&RigidSmallMembers::nmax_body); }
  static int get_bodysize(const F *f) { return f->*(&RigidSmallMembers::bodysize); }
  static int *get_atom2body(const F *f) { return f->*(&RigidSmallMembers::atom2body); }
  static int *get_bodyown(const F *f) { return f->*(&RigidSmallMembers::bodyown); }
  static double **get_displace(const F *f) { return f->*(&RigidSmallMembers::displace); }
  static double *get_mass_body(const F *f) { return f->*(&RigidSmallMembers::mass_body); }
  static int get_setupflag(const F *f) { return f->*(&RigidSmallMembers::setupflag); }
  static int get_reinitflag(const F *f) { return f->*(&RigidSmallMembers::reinitflag); }
  static const char *get_inpfile(const F *f) { return f->*(&RigidSmallMembers::inpfile); }
  static int get_langflag(const F *f) { return f->*(&RigidSmallMembers::langflag); }
  static double **get_langextra(const F *f) { return f->*(&RigidSmallMembers::langextra); }
};
// FixEfield keeps its field in protected members: the same way as for FixRigidSmall.
class EfieldMembers : public LAMMPS_NS::FixEfield {
 public:
  using F = LAMMPS_NS::FixEfield;
  static const double *get_field(const F *f, double e[3])
  {
    e[0] = f->*(&EfieldMembers::ex);
    e[1] = f->*(&EfieldMembers::ey);
    e[2] = f->*(&EfieldMembers::ez);
    return e;
  }
  static bool get_constant(const F *f)
  {
    return !(f->*(&EfieldMembers::xstr)) && !(f->*(&EfieldMembers::ystr)) && !(f->*(&EfieldMembers::zstr));
  }
  static bool get_region(const F *f) { return f->*(&EfieldMembers::idregion) != nullptr; }
  static double get_qe2f(const F *f) { return f->*(&EfieldMembers::qe2f); }
};
}    // namespace detail
#endif

// The bodies of a rigid/small (or rigid/nve/small) fix: read and written by fix clump/rigid
// for exact restarts, the first half-step of a run, and the clump geometry kspace kifmm needs.
// A thin handle on the fix (the arrays are read from it at every call, they move when
// rigid/small grows them); empty when constructed from nullptr.
class RigidSmallAccess {
 public:
#if KIFMM_LAMMPS_TREE
  using Body = detail::RigidSmallMembers::BodyType;
#else
  using Body = LAMMPS_NS::RigidSmallLayout::Body;
#endif

  RigidSmallAccess() = default;
  explicit RigidSmallAccess(LAMMPS_NS::Fix *rigid) : fix(rigid) {}
  explicit operator bool() const { return fix != nullptr; }

  // Empty when the internals of `rigid` can be used: a rigid/small fix that reads its bodies
  // from `infile`, whose bodies are set up and agree with what the fix itself reports
  // (extract("body"), extract("masstotal")). Otherwise why not. Not collective.
  static std::string check(LAMMPS_NS::LAMMPS *lmp, LAMMPS_NS::Fix *rigid,
                           const std::string &infile, LAMMPS_NS::tagint maxmol);

  Body *body() const;
  int nlocal_body() const;
  int nghost_body() const;
  int *atom2body() const;
  int *bodyown() const;
  double **displace() const;

  // Sum of the Langevin forces of rigid/small's langevin keyword on this rank's bodies, as
  // they enter the body forces (zero without the keyword). False when this LAMMPS does not
  // let it be read (Debian's: the layout does not reach that far).
  bool langevin_force(double sum[3]) const;

 private:
  LAMMPS_NS::Fix *fix = nullptr;
};

// Whether rigid/small's setup() puts the force of its gravity keyword into the body forces of
// the first half-step of a run: LAMMPS 29 Sep 2021 leaves it out, current LAMMPS puts it in.
// fix clump/rigid measures it at every run; this is what it assumes when it cannot.
constexpr bool rigid_small_setup_has_gravity = KIFMM_LAMMPS_DATE > 20210929;

// The uniform, constant field of a fix efield (style efield): e = its Ex Ey Ez times qe2f
// (force per charge, as the fix applies them). Empty when read, else why not (a field given by
// variables, a region; Debian's: a class layout that does not match). Not collective.
std::string efield_constant_field(LAMMPS_NS::LAMMPS *lmp, LAMMPS_NS::Fix *efield, double e[3]);

// Molecule templates: true when the members of Molecule can be used as declared (always with
// a tree's molecule.h; Debian's: the declared layout is checked on the templates `mols[0..nset)`
// of ID `id`, first `nmolecule_left` templates from there on).
bool molecule_members_ok(LAMMPS_NS::Molecule **mols, int nmolecule_left, const std::string &id);

}    // namespace kifmm_lammps
