// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "fix_clump_rigid.h"

#include "clump_bodies.h"
#include "clump_math.h"
#include "clump_template.h"
#include "clump_union.h"
#include "lammps_api.h"

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "domain.h"
#include "error.h"
#include "group.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "update.h"
#include "utils.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <unistd.h>

using namespace LAMMPS_NS;
using clump::Mat3;
using clump::Vec3;
using kifmm_lammps::RigidSmallAccess;

namespace {

// Columns of the per-clump compute rigid/local "<ID>_local" (documented in the doc page).
constexpr int restart_version = 1;
constexpr int restart_size = 5;    // version, density, tol, state stored, clumps

const char *const LOCAL_COLUMNS =
    "id mol mass x y z xu yu zu vx vy vz fx fy fz tqx tqy tqz omegax omegay omegaz "
    "angmomx angmomy angmomz quatw quati quatj quatk inertiax inertiay inertiaz";

// Collective: whether some atom is in the groups of both fixes.
bool share_atoms(LAMMPS *lmp, const Fix *a, const Fix *b)
{
  const int *mask = lmp->atom->mask;
  int mine = 0, any = 0;
  for (int i = 0; i < lmp->atom->nlocal && !mine; ++i)
    if ((mask[i] & a->groupbit) && (mask[i] & b->groupbit)) mine = 1;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, lmp->world);
  return any != 0;
}

// Collective: an error when another rigid-body fix (style rigid...) has atoms of the clump fix
// `self` in its group (both would integrate them). `own_rigid` is the ID of self's internal
// rigid fix; the internal rigid fix of another fix clump/rigid is named by that fix.
void check_other_rigid_fixes(LAMMPS *lmp, Fix *self, const std::string &own_rigid)
{
  Modify *modify = lmp->modify;
  for (int k = 0; k < modify->nfix; ++k) {
    Fix *other = modify->fix[k];
    if (other == self || own_rigid == other->id || !utils::strmatch(other->style, "^rigid")) continue;
    if (!share_atoms(lmp, self, other)) continue;
    Fix *named = other;
    for (int j = 0; j < modify->nfix; ++j)
      if (strcmp(modify->fix[j]->style, "clump/rigid") == 0 &&
          std::string(modify->fix[j]->id) + "_rigid" == other->id)
        named = modify->fix[j];
    lmp->error->all(FLERR,
                    "Fix clump/rigid {} and fix {} ({}) act on the same atoms (groups {} and {}): "
                    "an atom can belong to one rigid-body fix only",
                    self->id, named->id, named->style, lmp->group->names[self->igroup],
                    lmp->group->names[named->igroup]);
  }
}

// Collective: a warning for each fix defined after the rigid fix `rigid` that adds forces to
// atoms of the clump fix `self` (post_force: fix efield, fix addforce, ...). rigid/small sums
// the pebble forces in its own set-up, before the set-up of later fixes adds theirs, so their
// force is missing from the first half-step of every run.
void warn_later_force_fixes(LAMMPS *lmp, Fix *self, Fix *rigid)
{
  Modify *modify = lmp->modify;
  bool after = false;
  for (int k = 0; k < modify->nfix; ++k) {
    Fix *other = modify->fix[k];
    if (other == rigid) {
      after = true;
      continue;
    }
    if (!after || other->rigid_flag || !(other->setmask() & FixConst::POST_FORCE)) continue;
    if (share_atoms(lmp, self, other) && lmp->comm->me == 0)
      lmp->error->warning(FLERR,
                          "Fix clump/rigid {}: fix {} {} adds forces to its pebbles but is defined after it, "
                          "so its force is missing from the first half-step of every run (the rigid fix sums "
                          "the pebble forces at its set-up, before later fixes add theirs); define it before "
                          "fix clump/rigid",
                          self->id, other->style, other->id);
  }
}

}    // namespace

/* ---------------------------------------------------------------------- */

FixClumpRigid::FixClumpRigid(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
{
  vector_flag = 1;
  size_vector = 4;
  global_freq = 1;
  extvector = -1;    // the count is not normalized by thermo_modify norm, the energies are
  extlist = new int[4]{0, 1, 1, 1};
  restart_global = 1;
  restart_peratom = 1;
  wd_section = 1;
  create_attribute = 1;    // set_arrays() for created atoms: their clump values are not known
  maxexchange = 4 + NBV;

  if (narg < 5)
    error->all(FLERR, "Illegal fix clump/rigid command: expected density <rho> or infile <file>");

  int iarg = 3;
  while (iarg < narg) {
    std::string key = arg[iarg];
    auto need = [&](int n) {
      if (iarg + n >= narg)
        error->all(FLERR, "Illegal fix clump/rigid command: keyword {} needs {} value(s)", key,
                   n);
    };
    if (key == "density") {
      need(1);
      density = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      if (!(density > 0.0))
        error->all(FLERR, "Fix clump/rigid density must be > 0, got {}", arg[iarg + 1]);
      iarg += 2;
    } else if (key == "infile") {
      need(1);
      user_infile = arg[iarg + 1];
      iarg += 2;
    } else if (key == "mol") {
      need(1);
      template_id = arg[iarg + 1];
      iarg += 2;
    } else if (key == "tol") {
      need(1);
      tol = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      if (!(tol > 0.0 && tol < 0.1))
        error->all(FLERR, "Fix clump/rigid tol must be in (0, 0.1), got {}", arg[iarg + 1]);
      iarg += 2;
    } else if (key == "exclude") {
      need(1);
      std::string v = arg[iarg + 1];
      if (v == "yes") exclude = 1;
      else if (v == "no") exclude = 0;
      else error->all(FLERR, "Fix clump/rigid exclude must be yes or no, got {}", v);
      iarg += 2;
    } else if (key == "integrator") {
      need(1);
      std::string v = arg[iarg + 1];
      if (v == "small") integrator = "rigid/small";
      else if (v == "nve") integrator = "rigid/nve/small";
      else
        error->all(FLERR, "Fix clump/rigid integrator must be small or nve, got {}", v);
      iarg += 2;
    } else if (key == "langevin") {
      need(4);
      extra_args += fmt::format(" langevin {} {} {} {}", arg[iarg + 1], arg[iarg + 2],
                                arg[iarg + 3], arg[iarg + 4]);
      iarg += 5;
    } else if (key == "gravity") {
      need(1);
      extra_args += fmt::format(" gravity {}", arg[iarg + 1]);
      grav_id = arg[iarg + 1];
      iarg += 2;
    } else
      error->all(FLERR, "Illegal fix clump/rigid command: unknown keyword {}", key);
  }
  if ((density > 0.0) == !user_infile.empty())
    error->all(FLERR, "Fix clump/rigid needs exactly one of the keywords density and infile");

  if (!atom->molecule_flag)
    error->all(FLERR, "Fix clump/rigid requires atom attribute molecule (clump = molecule ID)");
  if (!atom->radius_flag)
    error->all(FLERR, "Fix clump/rigid requires atom attribute radius (atom_style sphere)");
  if (atom->map_style == Atom::MAP_NONE)
    error->all(FLERR, "Fix clump/rigid requires an atom map, see atom_modify map");

  // every pebble: radius > 0 and a molecule ID > 0 (rigid/small's infile cannot name body 0)
  int bad_radius = 0, bad_mol = 0;
  tagint mymax = 0;
  for (int i = 0; i < atom->nlocal; ++i) {
    if (!(atom->mask[i] & groupbit)) continue;
    if (!(atom->radius[i] > 0.0)) bad_radius = 1;
    if (atom->molecule[i] <= 0) bad_mol = 1;
    mymax = std::max(mymax, atom->molecule[i]);
  }
  MPI_Allreduce(&mymax, &maxmol, 1, MPI_LMP_TAGINT, MPI_MAX, world);
  int any[2] = {bad_radius, bad_mol}, all[2];
  MPI_Allreduce(any, all, 2, MPI_INT, MPI_MAX, world);
  if (all[0]) error->all(FLERR, "Fix clump/rigid: every pebble needs a radius > 0");
  if (all[1])
    error->all(FLERR, "Fix clump/rigid: every pebble needs a molecule ID > 0 (its clump)");

  id_rigid = std::string(id) + "_rigid";
  id_ke = std::string(id) + "_ke";
  id_erot = std::string(id) + "_erot";
  id_local = std::string(id) + "_local";

  if (!template_id.empty()) setup_templates();

  // pebbles of one clump never interact through the pair style
  if (exclude)
    neighbor->modify_params(fmt::format("exclude molecule/intra {}", group->names[igroup]));

  // restored body-frame offsets of the pebbles (restart files), moved with the atoms
  grow_arrays(atom->nmax);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
  for (int i = 0; i < atom->nlocal; ++i) set_arrays(i);

  // file through which rigid/small receives the mass properties (union or the user's infile),
  // motion and, after a restart, the stored state of the existing clumps
  {
    // unique per process and instance (several LAMMPS instances may share a process);
    // only rank 0's name matters: rigid/small reads its infile on rank 0
    static int instances = 0;
    long tag[2] = {(long) getpid(), (long) ++instances};
    MPI_Bcast(tag, 2, MPI_LONG, 0, world);
    std::error_code ec;
    auto dir = std::filesystem::temp_directory_path(ec);
    if (ec) dir = ".";
    std::string name = fmt::format("lammps_clump_rigid_{}_{}_{}.bodies", tag[0], tag[1], id);
    bodies_file = (dir / name).string();
    // the name goes into a LAMMPS command line: no whitespace
    if (bodies_file.find_first_of(" \t\n") != std::string::npos) bodies_file = name;
  }
}

/* ---------------------------------------------------------------------- */

FixClumpRigid::~FixClumpRigid()
{
  delete[] extlist;
  if (atom) {
    atom->delete_callback(id, Atom::GROW);
    atom->delete_callback(id, Atom::RESTART);
  }
  memory->destroy(rdisp);
  memory->destroy(bodyval);
  // the computes and the rigid fix are owned by this fix; they may already be gone when
  // LAMMPS is being destroyed or the user deleted them
  if (modify) {
    for (const auto &c : {id_local, id_erot, id_ke})
      if (!c.empty() && modify->find_compute(c) >= 0) modify->delete_compute(c);
    if (!id_rigid.empty() && modify->find_fix(id_rigid) >= 0) modify->delete_fix(id_rigid);
  }
  if (comm->me == 0 && !bodies_file.empty()) std::remove(bodies_file.c_str());
}

/* ---------------------------------------------------------------------- */

int FixClumpRigid::setmask()
{
  // all integration is done by the internal rigid fix; initial_integrate (before the rigid
  // fix's, this fix comes first) only completes the rigid fix's set-up: the gravity force of
  // the clumps, rigid/nve/small's conjqm
  // setup_post_neighbor puts a restored clump state back before the first forces of a run
  int mask = FixConst::POST_NEIGHBOR;
  if (integrator == "rigid/nve/small" || !grav_id.empty()) mask |= FixConst::INITIAL_INTEGRATE;
  return mask;
}

/* ---------------------------------------------------------------------- */

void FixClumpRigid::post_constructor()
{
  std::string cmd = fmt::format("{} {} {} molecule", id_rigid, group->names[igroup], integrator);
  cmd += " infile " + bodies_file;
  if (!template_id.empty()) cmd += " mol " + template_id;
  cmd += extra_args;
  modify->add_fix(cmd);
  modify->add_compute(fmt::format("{} {} ke/rigid {}", id_ke, group->names[igroup], id_rigid));
  modify->add_compute(
      fmt::format("{} {} erotate/rigid {}", id_erot, group->names[igroup], id_rigid));
  modify->add_compute(
      fmt::format("{} {} rigid/local {} {}", id_local, group->names[igroup], id_rigid,
                  LOCAL_COLUMNS));
  // the infile is written by init(), before rigid/small reads it at the first run's setup
}

/* ---------------------------------------------------------------------- */

Fix *FixClumpRigid::rigid_fix()
{
  int ifix = modify->find_fix(id_rigid);
  if (ifix < 0)
    error->all(FLERR, "Fix clump/rigid {}: its rigid fix {} was deleted", id, id_rigid);
  return modify->fix[ifix];
}

/* ---------------------------------------------------------------------- */

void FixClumpRigid::init()
{
  Fix *r = rigid_fix();
  check_other_rigid_fixes(lmp, this, id_rigid);
  warn_later_force_fixes(lmp, this, r);
  int dim;
  // clump values are computed again in every run (charges or pebbles may have changed), and
  // the pebble counts checked again
  counts_checked = false;
  bodies_rigid = nullptr;
  for (int i = 0; i < atom->nlocal; ++i) bodyval[i][BV_VALID] = 0.0;
  // rigid/small has not set up its bodies yet (it does so once, at the first run's setup,
  // from the infile): give it the clumps as they are now, positions and velocities, or the
  // state stored in the restart file
  if (r->extract("body", dim) != nullptr) return;
  if (restart_has_state) {
    restart_has_state = false;
    const bool same = (density > 0.0) ? restart_density == density : restart_density == 0.0;
    if (!same) {
      if (comm->me == 0)
        error->warning(FLERR,
                       "Fix clump/rigid {}: the restart file holds clumps of {}, the fix now "
                       "asks for {}: the stored clump state is not used, mass properties are "
                       "recomputed and the motion refitted",
                       id,
                       restart_density > 0.0 ? fmt::format("density {}", restart_density)
                                             : std::string("an infile"),
                       density > 0.0 ? fmt::format("density {}", density)
                                     : std::string("an infile"));
    } else {
      // every rank gets every stored clump (a clump's owner may have moved to another rank)
      int n = (int) rrecords.size(), nprocs = comm->nprocs;
      std::vector<int> counts(nprocs), displs(nprocs);
      MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, world);
      int total = 0;
      for (int p = 0; p < nprocs; ++p) {
        displs[p] = total;
        total += counts[p];
      }
      std::vector<double> all(total);
      MPI_Allgatherv(rrecords.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(),
                     MPI_DOUBLE, world);
      restored.clear();
      for (int k = 0; k + NREC <= total; k += NREC)
        restored[(tagint) all[k]] = std::vector<double>(all.begin() + k, all.begin() + k + NREC);
      rrecords.clear();
      write_restored_bodies_file();
      restore_pending = true;
      return;
    }
  }
  if (density > 0.0) write_bodies_file();
  else copy_user_infile();
}

/* ----------------------------------------------------------------------
   infile mode: rigid/small reads a copy of the user's file (so that after a restart it can
   read the stored state from the same file name instead)
------------------------------------------------------------------------- */

void FixClumpRigid::copy_user_infile()
{
  std::string errmsg;
  if (comm->me == 0) {
    std::ifstream in(user_infile, std::ios::binary);
    if (!in)
      errmsg = fmt::format("cannot open the infile {}", user_infile);
    else {
      std::ofstream out(bodies_file, std::ios::binary);
      out << in.rdbuf();
      out.close();
      if (!out) errmsg = fmt::format("cannot write the clump file {}", bodies_file);
    }
  }
  int len = (int) errmsg.size();
  MPI_Bcast(&len, 1, MPI_INT, 0, world);
  if (len > 0) {
    errmsg.resize(len);
    MPI_Bcast(&errmsg[0], len, MPI_CHAR, 0, world);
    error->all(FLERR, "Fix clump/rigid {}: {}", id, errmsg);
  }
}

/* ----------------------------------------------------------------------
   union mass properties of the molecule template(s), stored in the template so that
   rigid/small's set_molecule (fix pour, fix deposit) gives inserted clumps these values
------------------------------------------------------------------------- */

void FixClumpRigid::setup_templates()
{
  std::vector<char> name(template_id.begin(), template_id.end());
  name.push_back('\0');
  int imol = atom->find_molecule(name.data());
  if (imol < 0)
    error->all(FLERR, "Fix clump/rigid molecule template {} does not exist", template_id);
  Molecule **mols = &atom->molecules[imol];
  if (!kifmm_lammps::molecule_members_ok(mols, atom->nmolecule - imol, template_id))
    error->all(FLERR, "Fix clump/rigid: the Molecule class of this LAMMPS does not match the "
               "layout the package was built for");
  const int nset = mols[0]->nset;
  for (int m = 0; m < nset; ++m) {
    Molecule *mol = mols[m];
    if (mol->natoms < 1)
      error->all(FLERR, "Fix clump/rigid molecule template {} has no atoms", template_id);
    if (!mol->xflag || !mol->radiusflag)
      error->all(FLERR, "Fix clump/rigid molecule template {} needs Coords and Diameters "
                 "sections (pebble radii)", template_id);
    std::vector<clump::Sphere> s(mol->natoms);
    for (int i = 0; i < mol->natoms; ++i) {
      for (int d = 0; d < 3; ++d) s[i].x[d] = mol->x[i][d];
      s[i].r = mol->radius[i];
    }
    std::string why = clump::check_pebbles(s);
    if (!why.empty())
      error->all(FLERR, "Fix clump/rigid molecule template {}: {}", template_id, why);

    if (density > 0.0) {
      double t0 = MPI_Wtime();
      clump::MassProperties p = clump::union_mass_properties(s, density, tol);
      mol->masstotal = p.mass;
      for (int d = 0; d < 3; ++d) mol->com[d] = p.com[d];
      for (int k = 0; k < 6; ++k) mol->itensor[k] = p.itensor[k];
      mol->massflag = mol->comflag = mol->inertiaflag = 1;
      if (comm->me == 0)
        utils::logmesg(lmp,
                       "fix clump/rigid {}: template {} ({} pebbles): union volume {:.10g}, "
                       "mass {:.10g}, estimated relative error {:.2g}, {:.3f} s\n",
                       id, template_id, mol->natoms, p.volume, p.mass, p.rel_error,
                       MPI_Wtime() - t0);
    } else if (!(mol->massflag && mol->comflag && mol->inertiaflag)) {
      error->all(FLERR, "Fix clump/rigid with infile: molecule template {} must give mass, com "
                 "and inertia in its header", template_id);
    }
  }
}

/* ----------------------------------------------------------------------
   union mass properties, velocity and angular momentum of every existing clump, written in
   rigid/small's infile format (rank 0 gathers the pebbles and computes; clumps that are
   rotated copies of an already computed one reuse its result)
------------------------------------------------------------------------- */

void FixClumpRigid::write_bodies_file()
{
  const int nlocal = atom->nlocal;
  const int NV = 9;    // mol, tag, xu[3], v[3], radius
  std::vector<double> mine;
  int late = 0;
  for (int i = 0; i < nlocal; ++i) {
    if (!(atom->mask[i] & groupbit)) continue;
    // rigid/small made its bodies when the fix was defined; later clumps are not bodies
    if (atom->molecule[i] > maxmol) {
      late = 1;
      continue;
    }
    double xu[3];
    domain->unmap(atom->x[i], atom->image[i], xu);
    mine.insert(mine.end(), {(double) atom->molecule[i], (double) atom->tag[i], xu[0], xu[1],
                             xu[2], atom->v[i][0], atom->v[i][1], atom->v[i][2],
                             atom->radius[i]});
  }
  int any_late = 0;
  MPI_Allreduce(&late, &any_late, 1, MPI_INT, MPI_MAX, world);
  if (any_late && comm->me == 0)
    error->warning(FLERR, "Fix clump/rigid {}: pebbles with molecule IDs above {} were created "
                   "after the fix; they are not integrated (define the fix after the clumps)",
                   id, maxmol);
  int n = (int) mine.size(), nprocs = comm->nprocs;
  std::vector<int> counts(nprocs), displs(nprocs);
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, world);
  int total = 0;
  if (comm->me == 0)
    for (int p = 0; p < nprocs; ++p) {
      displs[p] = total;
      total += counts[p];
    }
  std::vector<double> all(comm->me == 0 ? total : 0);
  MPI_Gatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE,
              0, world);

  std::string errmsg;
  if (comm->me == 0) {
    const double t0 = MPI_Wtime();
    std::vector<clump::Pebble> pebbles(total / NV);
    for (std::size_t i = 0; i < pebbles.size(); ++i) {
      const double *a = &all[i * NV];
      pebbles[i] = {(long) a[0], (long) a[1], {a[2], a[3], a[4]}, {a[5], a[6], a[7]}, a[8]};
    }
    const clump::BodiesResult r = clump::compute_bodies(std::move(pebbles), density, tol);
    errmsg = r.error;
    if (errmsg.empty()) {
      std::ofstream f(bodies_file);
      f << clump::bodies_file_text(r.bodies, id, density);
      f.close();
      if (!f)
        errmsg = fmt::format("cannot write the clump file {}", bodies_file);
      else
        utils::logmesg(lmp,
                       "fix clump/rigid {}: {} clumps, {} distinct shapes integrated, "
                       "estimated relative error of the union mass <= {:.2g}, {:.3f} s\n",
                       id, r.bodies.size(), r.shapes_integrated, r.worst_rel_error, MPI_Wtime() - t0);
    }
  }
  int len = (int) errmsg.size();
  MPI_Bcast(&len, 1, MPI_INT, 0, world);
  if (len > 0) {
    errmsg.resize(len);
    MPI_Bcast(&errmsg[0], len, MPI_CHAR, 0, world);
    error->all(FLERR, "Fix clump/rigid {}: {}", id, errmsg);
  }
}

/* ---------------------------------------------------------------------- */

double FixClumpRigid::compute_vector(int i)
{
  auto scalar_of = [&](const std::string &cid) {
    int ic = modify->find_compute(cid);
    if (ic < 0) error->all(FLERR, "Fix clump/rigid {}: compute {} was deleted", id, cid);
    return modify->compute[ic]->compute_scalar();
  };
  switch (i) {
    case 0: {
      int ic = modify->find_compute(id_local);
      if (ic < 0) error->all(FLERR, "Fix clump/rigid {}: compute {} was deleted", id, id_local);
      Compute *c = modify->compute[ic];
      c->compute_local();
      double n = c->size_local_rows, sum = 0.0;
      MPI_Allreduce(&n, &sum, 1, MPI_DOUBLE, MPI_SUM, world);
      return sum;
    }
    case 1:
      return scalar_of(id_ke);
    case 2:
      return scalar_of(id_erot);
    case 3:
      return scalar_of(id_ke) + scalar_of(id_erot);
    default:
      return 0.0;
  }
}

/* ---------------------------------------------------------------------- */

void *FixClumpRigid::extract(const char *name, int &dim)
{
  // fix pour / fix deposit (rigid keyword naming this fix) check "onemol"; everything else
  // about the bodies is the rigid fix's too
  return rigid_fix()->extract(name, dim);
}

void FixClumpRigid::set_molecule(int nlocalprev, tagint tagprev, int imol, double *xgeom,
                                 double *vcm, double *quat)
{
  rigid_fix()->set_molecule(nlocalprev, tagprev, imol, xgeom, vcm, quat);
  // an inserted clump has the pebbles of its template (values computed when first needed)
  const int natoms = atom->molecules[imol]->natoms;
  for (int i = nlocalprev; i < atom->nlocal; ++i) {
    bodyval[i][BV_COUNT] = natoms;
    bodyval[i][BV_VALID] = 0.0;
  }
}

/* ----------------------------------------------------------------------
   rigid/small's internals, checked: empty (and why) when they cannot be used
------------------------------------------------------------------------- */

RigidSmallAccess FixClumpRigid::rigid_layout(std::string &why)
{
  Fix *r = rigid_fix();
  why = RigidSmallAccess::check(lmp, r, bodies_file, maxmol);
  return why.empty() ? RigidSmallAccess(r) : RigidSmallAccess();
}

/* ----------------------------------------------------------------------
   rigid/small infile from the stored clump state (the exact state is put back in setup())
------------------------------------------------------------------------- */

void FixClumpRigid::write_restored_bodies_file()
{
  std::string errmsg;
  if (comm->me == 0) {
    std::ostringstream out;
    out.precision(17);
    out << "# fix clump/rigid " << id << ": clump state from the restart file\n"
        << "# id mass xcm ycm zcm ixx iyy izz ixy ixz iyz vxcm vycm vzcm lx ly lz ixcm iycm "
           "izcm\n"
        << restored.size() << "\n";
    for (const auto &[mol, r] : restored) {
      // space-frame inertia P diag(I) P^T, P = (ex ey ez) as columns
      const double *in = &r[12], *ex = &r[15], *ey = &r[18], *ez = &r[21];
      double t[3][3];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          t[a][b] = ex[a] * in[0] * ex[b] + ey[a] * in[1] * ey[b] + ez[a] * in[2] * ez[b];
      const auto image = (imageint) r[34];
      const int xbox = (image & IMGMASK) - IMGMAX;
      const int ybox = (image >> IMGBITS & IMGMASK) - IMGMAX;
      const int zbox = (image >> IMG2BITS) - IMGMAX;
      out << (long) mol << ' ' << r[1] << ' ' << r[2] << ' ' << r[3] << ' ' << r[4] << ' '
          << t[0][0] << ' ' << t[1][1] << ' ' << t[2][2] << ' ' << t[0][1] << ' ' << t[0][2]
          << ' ' << t[1][2] << ' ' << r[5] << ' ' << r[6] << ' ' << r[7] << ' ' << r[24] << ' '
          << r[25] << ' ' << r[26] << ' ' << xbox << ' ' << ybox << ' ' << zbox << '\n';
    }
    std::ofstream f(bodies_file);
    f << out.str();
    f.close();
    if (!f) errmsg = fmt::format("cannot write the clump file {}", bodies_file);
  }
  int len = (int) errmsg.size();
  MPI_Bcast(&len, 1, MPI_INT, 0, world);
  if (len > 0) {
    errmsg.resize(len);
    MPI_Bcast(&errmsg[0], len, MPI_CHAR, 0, world);
    error->all(FLERR, "Fix clump/rigid {}: {}", id, errmsg);
  }
}

/* ----------------------------------------------------------------------
   called before rigid/small's setup() (this fix comes first in the fix list) and after its
   setup_pre_neighbor(), which has set the clumps up from the infile
------------------------------------------------------------------------- */

void FixClumpRigid::setup_post_neighbor()
{
  // after rigid/small's set-up from the clump file, before the forces of the run's set-up
  // (the kspace computes the clump values from the body-frame offsets put back here)
  if (restore_pending) {
    restore_pending = false;
    restore_state();
  }
}

void FixClumpRigid::setup(int)
{
  if (restore_pending) {    // minimization: no setup_post_neighbor call
    restore_pending = false;
    restore_state();
    for (int i = 0; i < atom->nlocal; ++i) bodyval[i][BV_VALID] = 0.0;    // offsets changed
  }
  // pebble counts of the clumps (if the kspace has not checked them in this run's set-up)
  if (!counts_checked) gather_clumps(nullptr, nullptr);
  // rigid/nve/small's setup() (after this one) recomputes conjqm from angmom: keep the
  // integrated (or restored) values and put them back before its first initial_integrate
  gravity_pending = !grav_id.empty();
  conjqm_hold.clear();
  if (integrator == "rigid/nve/small" && conjqm_valid) {
    std::string why;
    if (RigidSmallAccess v = rigid_layout(why))
      for (int b = 0; b < v.nlocal_body(); ++b) {
        const double *q = v.body()[b].conjqm;
        conjqm_hold.push_back({q[0], q[1], q[2], q[3]});
      }
  }
  // the pebble forces that rigid/small's setup() sums into the body forces, compared with
  // those at the first step; they are these forces when its setup() comes right after this one
  // (it does, unless this fix was defined again with the same ID: other fixes' setup() may
  // change the forces in between)
  if (gravity_pending) {
    int self = -1, rigid = -1;
    for (int k = 0; k < modify->nfix; ++k) {
      if (modify->fix[k] == this) self = k;
      if (id_rigid == modify->fix[k]->id) rigid = k;
    }
    grav_measured = self >= 0 && rigid == self + 1;
    std::string why;
    double mine[3] = {0.0, 0.0, 0.0};
    if (RigidSmallAccess v = grav_measured ? rigid_layout(why) : RigidSmallAccess()) {
      const int *a2b = v.atom2body();
      for (int i = 0; i < atom->nlocal; ++i)
        if (a2b[i] >= 0)
          for (int d = 0; d < 3; ++d) mine[d] += atom->f[i][d];
    }
    MPI_Allreduce(mine, grav_fsum, 3, MPI_DOUBLE, MPI_SUM, world);
  }
}

void FixClumpRigid::initial_integrate(int)
{
  if (gravity_pending) {
    gravity_pending = false;
    // rigid/small's setup() summed the pebble forces into fcm without the clump weight that
    // its final_integrate adds (fcm += g M): add it, so that a run split into two runs (or by
    // a restart) equals the unsplit run
    int ig = modify->find_fix(grav_id), dim = 0;
    auto *g = ig >= 0 ? static_cast<double *>(modify->fix[ig]->extract("gvec", dim)) : nullptr;
    std::string why;
    RigidSmallAccess v = g ? rigid_layout(why) : RigidSmallAccess();
    int usable = v ? 1 : 0, all_usable = 0;
    MPI_Allreduce(&usable, &all_usable, 1, MPI_INT, MPI_MIN, world);
    if (all_usable) {
      // whether rigid/small's setup() has put the weight into the body forces already: their
      // sum is the pebble forces' (left out), or that plus the weight and, where readable,
      // the Langevin forces (put in)
      bool included = kifmm_lammps::rigid_small_setup_has_gravity;
      if (grav_measured) {
        double mine[9] = {0.0}, sum[9];
        for (int b = 0; b < v.nlocal_body(); ++b)
          for (int d = 0; d < 3; ++d) {
            mine[d] += v.body()[b].fcm[d];
            mine[3 + d] += g[d] * v.body()[b].mass;
          }
        v.langevin_force(&mine[6]);
        MPI_Allreduce(mine, sum, 9, MPI_DOUBLE, MPI_SUM, world);
        auto dist = [&](double w, double l) {
          double r = 0.0;
          for (int d = 0; d < 3; ++d) {
            const double e = sum[d] - grav_fsum[d] - w * sum[3 + d] - l * sum[6 + d];
            r += e * e;
          }
          return r;
        };
        included = std::min(dist(1, 0), dist(1, 1)) <= std::min(dist(0, 0), dist(0, 1));
      }
      if (!included)
        for (int b = 0; b < v.nlocal_body(); ++b) {
          auto &body = v.body()[b];
          body.fcm[0] += g[0] * body.mass;
          body.fcm[1] += g[1] * body.mass;
          body.fcm[2] += g[2] * body.mass;
        }
    } else if (comm->me == 0 && !restart_warned) {
      restart_warned = true;
      error->warning(FLERR,
                     "Fix clump/rigid {}: cannot add the clump weight to the first half-step "
                     "of the run ({}): the clumps lag by g dt/2",
                     id, !g ? std::string("no gravity vector")
                            : why.empty() ? std::string("on another rank") : why);
    }
  }
  if (!conjqm_hold.empty()) {
    std::string why;
    RigidSmallAccess v = rigid_layout(why);
    if (v && v.nlocal_body() == (int) conjqm_hold.size())
      for (int b = 0; b < v.nlocal_body(); ++b)
        for (int k = 0; k < 4; ++k) v.body()[b].conjqm[k] = conjqm_hold[b][k];
    conjqm_hold.clear();
  }
  conjqm_valid = true;
}

void FixClumpRigid::restore_state()
{
  std::string why;
  RigidSmallAccess v = rigid_layout(why);
  int bad = v ? 0 : 1, anybad = 0;
  MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_MAX, world);
  if (anybad) {
    if (comm->me == 0)
      error->warning(FLERR,
                     "Fix clump/rigid {}: cannot put the stored clump state back ({}); the run "
                     "continues from the clump file (equal to the stored state to roundoff)",
                     id, why.empty() ? "on another rank" : why);
    restored.clear();
    return;
  }
  int missing = 0, nset = 0;
  for (int b = 0; b < v.nlocal_body() + v.nghost_body(); ++b) {
    auto &body = v.body()[b];
    auto it = restored.find(atom->molecule[body.ilocal]);
    if (it == restored.end()) {
      if (b < v.nlocal_body()) ++missing;
      continue;
    }
    const double *r = it->second.data();
    body.mass = r[1];
    for (int d = 0; d < 3; ++d) {
      body.xcm[d] = r[2 + d];
      body.vcm[d] = r[5 + d];
      body.inertia[d] = r[12 + d];
      body.ex_space[d] = r[15 + d];
      body.ey_space[d] = r[18 + d];
      body.ez_space[d] = r[21 + d];
      body.angmom[d] = r[24 + d];
      body.omega[d] = r[27 + d];
    }
    for (int k = 0; k < 4; ++k) {
      body.quat[k] = r[8 + k];
      if (integrator == "rigid/nve/small") body.conjqm[k] = r[30 + k];
    }
    body.image = (imageint) r[34];
    if (b < v.nlocal_body()) ++nset;
  }
  for (int i = 0; i < atom->nlocal; ++i) {
    if (v.atom2body()[i] < 0) continue;
    if (rdisp[i][3] == 0.0) {
      ++missing;
      continue;
    }
    for (int d = 0; d < 3; ++d) v.displace()[i][d] = rdisp[i][d];
    rdisp[i][3] = 0.0;
  }
  int counts[2] = {nset, missing}, all[2];
  MPI_Allreduce(counts, all, 2, MPI_INT, MPI_SUM, world);
  restored.clear();
  conjqm_valid = true;    // restored (rigid/nve/small)
  if (comm->me == 0) {
    if (all[1] > 0)
      error->warning(FLERR,
                     "Fix clump/rigid {}: {} clumps or pebbles were not in the restart file; "
                     "they continue from the clump file",
                     id, all[1]);
    utils::logmesg(lmp, "fix clump/rigid {}: state of {} clumps restored from the restart file\n",
                   id, all[0]);
  }
}

/* ---------------------------------------------------------------------- */

void FixClumpRigid::write_restart(FILE *fp)
{
  // the clump state exists once rigid/small has set its bodies up (first run)
  int dim;
  int exact = 0;
  std::string why;
  if (rigid_fix()->extract("body", dim) != nullptr) {
    exact = rigid_layout(why) ? 1 : 0;
    int all;
    MPI_Allreduce(&exact, &all, 1, MPI_INT, MPI_MIN, world);
    if (!all && comm->me == 0 && !restart_warned) {
      restart_warned = true;
      error->warning(FLERR,
                     "Fix clump/rigid {}: the restart file cannot hold the exact clump state "
                     "({}); a restarted run recomputes it",
                     id, why.empty() ? "on another rank" : why);
    }
    exact = all;
  }
  write_exact = exact != 0;
  double list[restart_size] = {(double) restart_version, density, tol, (double) exact, 0.0};
  if (exact) {
    double n = RigidSmallAccess(rigid_fix()).nlocal_body(), total = 0.0;
    MPI_Allreduce(&n, &total, 1, MPI_DOUBLE, MPI_SUM, world);
    list[4] = total;
  }
  if (comm->me == 0) {
    int size = restart_size * sizeof(double);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), restart_size, fp);
  }
}

void FixClumpRigid::restart(char *buf)
{
  const auto *list = reinterpret_cast<const double *>(buf);
  if ((int) list[0] != restart_version)
    error->all(FLERR, "Fix clump/rigid {}: restart data of version {} (expected {})", id,
               (int) list[0], restart_version);
  restart_density = list[1];
  restart_has_state = list[3] != 0.0;
}

int FixClumpRigid::size_restart(int i)
{
  if (!write_exact || !(atom->mask[i] & groupbit)) return 2;
  RigidSmallAccess v(rigid_fix());
  if (v.atom2body()[i] < 0) return 2;
  return v.bodyown()[i] >= 0 ? 5 + NREC : 5;
}

int FixClumpRigid::maxsize_restart()
{
  return 5 + NREC;
}

int FixClumpRigid::pack_restart(int i, double *buf)
{
  const int n = size_restart(i);
  buf[0] = n;    // the count first: other fixes skip over it
  buf[1] = n == 2 ? 0 : (n == 5 ? 1 : 2);
  if (n == 2) return n;
  RigidSmallAccess v(rigid_fix());
  for (int d = 0; d < 3; ++d) buf[2 + d] = v.displace()[i][d];
  if (n == 5) return n;
  const auto &b = v.body()[v.bodyown()[i]];
  double *r = buf + 5;
  r[0] = (double) atom->molecule[i];
  r[1] = b.mass;
  for (int d = 0; d < 3; ++d) {
    r[2 + d] = b.xcm[d];
    r[5 + d] = b.vcm[d];
    r[12 + d] = b.inertia[d];
    r[15 + d] = b.ex_space[d];
    r[18 + d] = b.ey_space[d];
    r[21 + d] = b.ez_space[d];
    r[24 + d] = b.angmom[d];
    r[27 + d] = b.omega[d];
  }
  // conjqm is state only for rigid/nve/small (rigid/small never sets it: uninitialised)
  const bool nve = integrator == "rigid/nve/small";
  for (int k = 0; k < 4; ++k) {
    r[8 + k] = b.quat[k];
    r[30 + k] = nve ? b.conjqm[k] : 0.0;
  }
  r[34] = (double) b.image;
  return n;
}

void FixClumpRigid::unpack_restart(int nlocal, int nth)
{
  double **extra = atom->extra;
  int m = 0;
  for (int k = 0; k < nth; ++k) m += static_cast<int>(extra[nlocal][m]);
  const double *buf = &extra[nlocal][m];
  const int n = static_cast<int>(buf[0]), status = static_cast<int>(buf[1]);
  if (!((n == 2 && status == 0) || (n == 5 && status == 1) || (n == 5 + NREC && status == 2)))
    error->one(FLERR, "Fix clump/rigid {}: per-atom restart data of unexpected size", id);
  if (status == 0) return;
  for (int d = 0; d < 3; ++d) rdisp[nlocal][d] = buf[2 + d];
  rdisp[nlocal][3] = 1.0;
  if (status == 2) rrecords.insert(rrecords.end(), buf + 5, buf + 5 + NREC);
}

/* ---------------------------------------------------------------------- */

void FixClumpRigid::grow_arrays(int nmax)
{
  memory->grow(rdisp, nmax, 4, "clump/rigid:rdisp");
  memory->grow(bodyval, nmax, NBV, "clump/rigid:bodyval");
}

void FixClumpRigid::copy_arrays(int i, int j, int)
{
  for (int k = 0; k < 4; ++k) rdisp[j][k] = rdisp[i][k];
  for (int k = 0; k < NBV; ++k) bodyval[j][k] = bodyval[i][k];
}

void FixClumpRigid::set_arrays(int i)
{
  for (int k = 0; k < 4; ++k) rdisp[i][k] = 0.0;
  for (int k = 0; k < NBV; ++k) bodyval[i][k] = 0.0;
}

int FixClumpRigid::pack_exchange(int i, double *buf)
{
  for (int k = 0; k < 4; ++k) buf[k] = rdisp[i][k];
  for (int k = 0; k < NBV; ++k) buf[4 + k] = bodyval[i][k];
  return 4 + NBV;
}

int FixClumpRigid::unpack_exchange(int nlocal, double *buf)
{
  for (int k = 0; k < 4; ++k) rdisp[nlocal][k] = buf[k];
  for (int k = 0; k < NBV; ++k) bodyval[nlocal][k] = buf[4 + k];
  return 4 + NBV;
}

double FixClumpRigid::memory_usage()
{
  return (double) atom->nmax * (4 + NBV) * sizeof(double);
}

/* ----------------------------------------------------------------------
   write_data: data files have no place for rigid bodies in this LAMMPS (rigid/small writes
   none either). The pebbles and their molecule IDs (fix property/atom) are written; this fix
   adds a comment (read_data skips it) and warns.
------------------------------------------------------------------------- */

void FixClumpRigid::write_data_section_size(int, int &nx, int &ny)
{
  nx = 0;
  ny = 1;
}

void FixClumpRigid::write_data_section_pack(int, double **) {}

void FixClumpRigid::write_data_section_keyword(int, FILE *fp)
{
  fmt::print(fp,
             "\n# fix clump/rigid {}: clumps are the molecules of group {}; the clump state "
             "(mass properties, orientation, motion) is not in this file.\n# After read_data "
             "define fix clump/rigid again (mass properties are recomputed, the clump motion is "
             "refitted to the pebble velocities).\n",
             id, group->names[igroup]);
  error->warning(FLERR,
                 "Fix clump/rigid {}: write_data stores the pebbles and their molecule IDs, not "
                 "the clump state; after read_data define the fix again (mass properties "
                 "recomputed, motion refitted); write_restart keeps the exact state",
                 id);
}

void FixClumpRigid::write_data_section(int, FILE *, int, double **, int) {}
