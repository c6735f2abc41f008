// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix clump/rigid as KIFMMRigidBodies: the pebbles of every clump gathered on one rank
// (LAMMPS's rendezvous communication, clump ID -> rank), their pair sums computed there in the
// body frame and sent back to the pebbles' owners; the pebble count of every clump checked
// against the count its mass properties were computed for.
#include "fix_clump_rigid.h"

#include "lammps_api.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "memory.h"

#include <algorithm>
#include <numeric>
#include <vector>

using namespace LAMMPS_NS;
using kifmm_lammps::RigidSmallAccess;

namespace {

struct PebbleIn {
  tagint mol, tag;
  int proc, count;    // owner rank; pebble count of the clump when first checked (0: not yet)
  double d[3], s;     // body-frame offset, strength
};

struct PebbleOut {
  tagint mol, tag;
  int count, stored;    // pebbles of the clump now; `count` of PebbleIn
  double s;
  double v[KIFMMRigidBodies::nvalues];
};

}    // namespace

/* ---------------------------------------------------------------------- */

bool FixClumpRigid::bodies_ready(std::string &why)
{
  why.clear();
  bodies_rigid = rigid_layout(why) ? rigid_fix() : nullptr;
  int bad = bodies_rigid ? 0 : 1, anybad = 0;
  MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_MAX, world);
  if (anybad && why.empty()) why = "not on another rank";
  if (anybad) bodies_rigid = nullptr;
  return !anybad;
}

const double *FixClumpRigid::body_values(int i) const
{
  if (!bodies_rigid || !(atom->mask[i] & groupbit) ||
      RigidSmallAccess(bodies_rigid).atom2body()[i] < 0)
    return nullptr;
  return bodyval[i];
}

void FixClumpRigid::body_frame(int i, double rotation[9], double offset[3]) const
{
  const RigidSmallAccess v(bodies_rigid);
  const auto &b = v.body()[v.atom2body()[i]];
  const double *axis[3] = {b.ex_space, b.ey_space, b.ez_space};
  const double *d = v.displace()[i];
  for (int a = 0; a < 3; ++a) {
    offset[a] = 0.0;
    for (int c = 0; c < 3; ++c) {
      rotation[3 * a + c] = axis[c][a];
      offset[a] += axis[c][a] * d[c];
    }
  }
}

tagint FixClumpRigid::body_tag(int i) const
{
  if (!bodies_rigid || !(atom->mask[i] & groupbit) ||
      RigidSmallAccess(bodies_rigid).atom2body()[i] < 0)
    return 0;
  return atom->molecule[i];
}

void FixClumpRigid::compute_body_values(const Strength &strength, const BodyFunction &f)
{
  gather_clumps(&strength, &f);
}

/* ----------------------------------------------------------------------
   rendezvous: every pebble of a clump on the rank clump ID % nprocs; with a body function
   (needs the rigid/small layout: body-frame offsets) the values of each clump, always the
   pebble count
------------------------------------------------------------------------- */

void FixClumpRigid::gather_clumps(const Strength *strength, const BodyFunction *f)
{
  if (f && !bodies_rigid)
    error->all(FLERR, "Fix clump/rigid {}: clump geometry requested before its bodies are ready", id);
  const int nlocal = atom->nlocal, nprocs = comm->nprocs;
  const RigidSmallAccess v(f ? bodies_rigid : nullptr);
  std::vector<PebbleIn> in;
  std::vector<int> procs;
  for (int i = 0; i < nlocal; ++i) {
    if (!(atom->mask[i] & groupbit)) continue;
    if (f ? v.atom2body()[i] < 0 : atom->molecule[i] > maxmol) continue;
    PebbleIn p;
    p.mol = atom->molecule[i];
    p.tag = atom->tag[i];
    p.proc = comm->me;
    p.count = (int) bodyval[i][BV_COUNT];
    for (int d = 0; d < 3; ++d) p.d[d] = f ? v.displace()[i][d] : 0.0;
    p.s = strength ? (*strength)(i) : 0.0;
    in.push_back(p);
    procs.push_back((int) (p.mol % nprocs));
  }
  rendezvous_function = f;
  char *outbuf = nullptr;
  const int nout = comm->rendezvous(1, (int) in.size(), reinterpret_cast<char *>(in.data()),
                                    sizeof(PebbleIn), 0, procs.data(), clump_callback, 0, outbuf,
                                    sizeof(PebbleOut), (void *) this);
  rendezvous_function = nullptr;
  const auto *out = reinterpret_cast<const PebbleOut *>(outbuf);
  // the clump of smallest ID whose pebble count changed (ID, count, stored count)
  bigint bad[3] = {MAXBIGINT, 0, 0};
  for (int k = 0; k < nout; ++k) {
    const PebbleOut &o = out[k];
    const int i = atom->map(o.tag);
    if (i < 0 || i >= nlocal) continue;
    if (o.stored > 0 && o.stored != o.count) {
      if (o.mol < bad[0]) bad[0] = o.mol, bad[1] = o.count, bad[2] = o.stored;
      continue;
    }
    bodyval[i][BV_COUNT] = o.count;
    if (!f) continue;
    for (int c = 0; c < nvalues; ++c) bodyval[i][c] = o.v[c];
    bodyval[i][BV_STRENGTH] = o.s;
    bodyval[i][BV_VALID] = 1.0;
  }
  memory->sfree(outbuf);
  counts_checked = true;

  bigint first = 0;
  MPI_Allreduce(&bad[0], &first, 1, MPI_LMP_BIGINT, MPI_MIN, world);
  if (first == MAXBIGINT) return;
  bigint mine[2] = {bad[0] == first ? bad[1] : 0, bad[0] == first ? bad[2] : 0}, all[2];
  MPI_Allreduce(mine, all, 2, MPI_LMP_BIGINT, MPI_MAX, world);
  error->all(FLERR,
             "Fix clump/rigid {}: clump {} has {} pebbles, its mass properties were computed for "
             "{} (pebbles deleted or added after the clumps were set up, e.g. by delete_atoms); "
             "define the clumps again (unfix and fix clump/rigid) to recompute them",
             id, first, all[0], all[1]);
}

int FixClumpRigid::clump_callback(int n, char *inbuf, int &flag, int *&proclist, char *&outbuf,
                                  void *ptr)
{
  auto *self = static_cast<FixClumpRigid *>(ptr);
  const auto *in = reinterpret_cast<const PebbleIn *>(inbuf);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return in[a].mol != in[b].mol ? in[a].mol < in[b].mol : in[a].tag < in[b].tag;
  });
  self->memory->create(proclist, std::max(n, 1), "clump/rigid:proclist");
  auto *out = static_cast<PebbleOut *>(
      self->memory->smalloc((bigint) std::max(n, 1) * sizeof(PebbleOut), "clump/rigid:outbuf"));
  const BodyFunction *f = self->rendezvous_function;
  std::vector<double> d, s, v;
  for (int a = 0; a < n;) {
    int b = a;
    while (b < n && in[order[b]].mol == in[order[a]].mol) ++b;
    const int m = b - a;
    d.resize(3 * m);
    s.resize(m);
    v.assign((std::size_t) nvalues * m, 0.0);
    for (int k = 0; k < m; ++k) {
      const PebbleIn &p = in[order[a + k]];
      for (int c = 0; c < 3; ++c) d[3 * k + c] = p.d[c];
      s[k] = p.s;
    }
    if (f && *f) (*f)(m, d.data(), s.data(), v.data());
    for (int k = 0; k < m; ++k) {
      const PebbleIn &p = in[order[a + k]];
      PebbleOut &o = out[order[a + k]];
      o.mol = p.mol;
      o.tag = p.tag;
      o.count = m;
      o.stored = p.count;
      o.s = p.s;
      for (int c = 0; c < nvalues; ++c) o.v[c] = v[(std::size_t) nvalues * k + c];
      proclist[order[a + k]] = p.proc;
    }
    a = b;
  }
  outbuf = reinterpret_cast<char *>(out);
  flag = 2;
  return n;
}
