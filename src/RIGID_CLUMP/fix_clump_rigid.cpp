#include "fix_clump_rigid.h"

#include "clump_math.h"
#include "clump_union.h"
#include "molecule_layout.h"

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "domain.h"
#include "error.h"
#include "group.h"
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

namespace {

// Columns of the per-clump compute rigid/local "<ID>_local" (documented in the doc page).
const char *const LOCAL_COLUMNS =
    "id mol mass x y z xu yu zu vx vy vz fx fy fz tqx tqy tqz omegax omegay omegaz "
    "angmomx angmomy angmomz quatw quati quatj quatk inertiax inertiay inertiaz";

Mat3 itensor_to_matrix(const double t[6])
{
  // LAMMPS order xx yy zz yz xz xy, off-diagonal entries are the tensor's own
  Mat3 m;
  m[0] = {t[0], t[5], t[4]};
  m[1] = {t[5], t[1], t[3]};
  m[2] = {t[4], t[3], t[2]};
  return m;
}

void matrix_to_itensor(const Mat3 &m, double t[6])
{
  t[0] = m[0][0];
  t[1] = m[1][1];
  t[2] = m[2][2];
  t[3] = 0.5 * (m[1][2] + m[2][1]);
  t[4] = 0.5 * (m[0][2] + m[2][0]);
  t[5] = 0.5 * (m[0][1] + m[1][0]);
}

std::string duplicates_message(const std::vector<clump::Sphere> &s,
                               const std::vector<std::array<int, 2>> &dups,
                               const std::vector<long> &labels)
{
  std::ostringstream msg;
  const auto &d = dups.front();
  msg << dups.size() << " pair(s) of duplicate (coincident) pebbles, first: pebbles "
      << labels[d[0]] << " and " << labels[d[1]] << " at (" << s[d[0]].x[0] << ", "
      << s[d[0]].x[1] << ", " << s[d[0]].x[2] << ")";
  return msg.str();
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

  // file through which rigid/small receives the union mass properties of existing clumps
  if (density > 0.0) {
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
  return 0;    // all integration is done by the internal rigid fix
}

/* ---------------------------------------------------------------------- */

void FixClumpRigid::post_constructor()
{
  std::string cmd = fmt::format("{} {} {} molecule", id_rigid, group->names[igroup], integrator);
  if (density > 0.0) cmd += " infile " + bodies_file;
  else cmd += " infile " + user_infile;
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
  int dim;
  // rigid/small has not set up its bodies yet (it does so once, at the first run's setup,
  // from the infile): give it the clumps as they are now, positions and velocities
  if (density > 0.0 && r->extract("body", dim) == nullptr) write_bodies_file();
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
  if (strcmp(mols[0]->id, template_id.c_str()) != 0 || mols[0]->nset < 1 ||
      mols[0]->nset > atom->nmolecule - imol)
    error->all(FLERR, "Fix clump/rigid: the Molecule class of this LAMMPS does not match the "
               "layout the package was built for");
  const int nset = mols[0]->nset;
  for (int m = 0; m < nset; ++m) {
    Molecule *mol = mols[m];
    auto is01 = [](int f) { return f == 0 || f == 1; };
    bool ok = mol->natoms > 0 && is01(mol->xflag) && is01(mol->radiusflag) &&
        is01(mol->massflag) && is01(mol->comflag) && is01(mol->inertiaflag) && is01(mol->qflag);
    if (ok && mol->xflag) {
      // compute_center() (LAMMPS's own code) must put the mean of x into center
      mol->compute_center();
      double c[3] = {0, 0, 0}, ext = 0.0;
      for (int i = 0; i < mol->natoms; ++i)
        for (int d = 0; d < 3; ++d) c[d] += mol->x[i][d] / mol->natoms;
      for (int i = 0; i < mol->natoms; ++i)
        for (int d = 0; d < 3; ++d) ext = std::max(ext, std::fabs(mol->x[i][d] - c[d]));
      for (int d = 0; d < 3; ++d)
        if (std::fabs(c[d] - mol->center[d]) > 1e-9 * (ext + 1e-300) + 1e-300) ok = false;
    }
    if (!ok)
      error->all(FLERR, "Fix clump/rigid: the Molecule class of this LAMMPS does not match the "
                 "layout the package was built for");
    if (!mol->xflag || !mol->radiusflag)
      error->all(FLERR, "Fix clump/rigid molecule template {} needs Coords and Diameters "
                 "sections (pebble radii)", template_id);
    std::vector<clump::Sphere> s(mol->natoms);
    std::vector<long> labels(mol->natoms);
    for (int i = 0; i < mol->natoms; ++i) {
      for (int d = 0; d < 3; ++d) s[i].x[d] = mol->x[i][d];
      s[i].r = mol->radius[i];
      labels[i] = i + 1;
      if (!(s[i].r > 0.0))
        error->all(FLERR, "Fix clump/rigid molecule template {}: pebble {} has diameter <= 0",
                   template_id, i + 1);
    }
    auto dups = clump::duplicate_spheres(s);
    if (!dups.empty())
      error->all(FLERR, "Fix clump/rigid molecule template {}: {}", template_id,
                 duplicates_message(s, dups, labels));

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
    double t0 = MPI_Wtime();
    const int natoms = total / NV;
    std::vector<int> order(natoms);
    for (int i = 0; i < natoms; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      if (all[a * NV] != all[b * NV]) return all[a * NV] < all[b * NV];
      return all[a * NV + 1] < all[b * NV + 1];
    });
    double rmax = 0.0;
    for (int i = 0; i < natoms; ++i) rmax = std::max(rmax, all[i * NV + 8]);

    struct Shape {
      std::vector<Vec3> ref;    // pebble centres relative to their centroid
      double spread;            // sum of |ref|^2 (rotation invariant, quick pre-check)
      double mass, volume, rel_error;
      Vec3 com;      // relative to the centroid
      Mat3 inertia;  // about the COM
    };
    std::map<std::vector<long long>, std::vector<Shape>> cache;
    int ncomputed = 0, nclumps = 0;
    double worst_error = 0.0;
    std::ostringstream out;
    out.precision(17);
    std::ostringstream lines;
    lines.precision(17);

    for (int start = 0; start < natoms && errmsg.empty();) {
      int end = start;
      const double mol = all[order[start] * NV];
      while (end < natoms && all[order[end] * NV] == mol) ++end;
      const int np = end - start;
      std::vector<clump::Sphere> s(np);
      std::vector<Vec3> x(np), v(np);
      std::vector<long> labels(np);
      std::vector<long long> key = {np};
      double rmin = 1e300;
      Vec3 g{0, 0, 0};
      for (int k = 0; k < np; ++k) {
        const double *a = &all[order[start + k] * NV];
        labels[k] = (long) a[1];
        for (int d = 0; d < 3; ++d) {
          s[k].x[d] = a[2 + d];
          x[k][d] = a[2 + d];
          v[k][d] = a[5 + d];
          g[d] += a[2 + d] / np;
        }
        s[k].r = a[8];
        rmin = std::min(rmin, a[8]);
        key.push_back(std::llround(a[8] / rmax * 1e9));
      }
      auto dups = clump::duplicate_spheres(s);
      if (!dups.empty()) {
        errmsg = fmt::format("clump (molecule ID) {}: {} (atom IDs)", (long) mol,
                             duplicates_message(s, dups, labels));
        break;
      }
      std::vector<Vec3> rel(np);
      double spread = 0.0;
      for (int k = 0; k < np; ++k)
        for (int d = 0; d < 3; ++d) {
          rel[k][d] = x[k][d] - g[d];
          spread += rel[k][d] * rel[k][d];
        }
      const double match = 1e-4 * rmin;    // rms distance for "same shape"

      // reuse a computed shape if this clump is a rotated copy of it
      double mass = 0.0, rel_error = 0.0;
      Vec3 com{};
      Mat3 inertia{};
      bool found = false;
      auto &candidates = cache[key];
      for (const Shape &sh : candidates) {
        // |sqrt(spread) - sqrt(sh.spread)| <= rms-fit residual * sqrt(np)
        if (std::fabs(std::sqrt(spread) - std::sqrt(sh.spread)) > match * std::sqrt((double) np))
          continue;
        double rms;
        Mat3 rot = clump::best_rotation(sh.ref, rel, rms);
        if (rms > match) continue;
        Vec3 c = clump::matvec(rot, sh.com);
        for (int d = 0; d < 3; ++d) com[d] = g[d] + c[d];
        inertia = clump::matmul(clump::matmul(rot, sh.inertia), clump::transpose(rot));
        mass = sh.mass;
        rel_error = sh.rel_error;
        found = true;
        break;
      }
      if (!found) {
        std::vector<clump::Sphere> sl(s);
        for (int k = 0; k < np; ++k)
          for (int d = 0; d < 3; ++d) sl[k].x[d] = rel[k][d];
        clump::MassProperties p = clump::union_mass_properties(sl, density, tol);
        Shape sh;
        sh.ref = rel;
        sh.spread = spread;
        sh.mass = p.mass;
        sh.volume = p.volume;
        sh.rel_error = p.rel_error;
        sh.com = {p.com[0], p.com[1], p.com[2]};
        sh.inertia = itensor_to_matrix(p.itensor);
        candidates.push_back(sh);
        ++ncomputed;
        mass = p.mass;
        rel_error = p.rel_error;
        for (int d = 0; d < 3; ++d) com[d] = g[d] + sh.com[d];
        inertia = sh.inertia;
      }
      worst_error = std::max(worst_error, rel_error);

      // rigid motion of the pebbles: velocity of the COM and angular momentum L = I omega
      Vec3 vcm, omega;
      clump::fit_rigid_motion(x, v, com, vcm, omega);
      Vec3 angmom = clump::matvec(inertia, omega);
      double it[6];
      matrix_to_itensor(inertia, it);
      lines << (long) mol << ' ' << mass << ' ' << com[0] << ' ' << com[1] << ' ' << com[2]
            << ' ' << it[0] << ' ' << it[1] << ' ' << it[2] << ' ' << it[5] << ' ' << it[4]
            << ' ' << it[3] << ' ' << vcm[0] << ' ' << vcm[1] << ' ' << vcm[2] << ' '
            << angmom[0] << ' ' << angmom[1] << ' ' << angmom[2] << " 0 0 0\n";
      ++nclumps;
      start = end;
    }
    if (errmsg.empty()) {
      out << "# fix clump/rigid " << id << ": union-of-spheres mass properties at density "
          << density << "\n"
          << "# id mass xcm ycm zcm ixx iyy izz ixy ixz iyz vxcm vycm vzcm lx ly lz ixcm iycm "
             "izcm\n"
          << nclumps << "\n"
          << lines.str();
      std::ofstream f(bodies_file);
      f << out.str();
      f.close();
      if (!f)
        errmsg = fmt::format("cannot write the clump file {}", bodies_file);
      else
        utils::logmesg(lmp,
                       "fix clump/rigid {}: {} clumps, {} distinct shapes integrated, "
                       "estimated relative error of the union mass <= {:.2g}, {:.3f} s\n",
                       id, nclumps, ncomputed, worst_error, MPI_Wtime() - t0);
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
}
