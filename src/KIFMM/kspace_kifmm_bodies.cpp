// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// kspace_style kifmm and rigid bodies (fix clump/rigid, through KIFMMRigidBodies): the pairs
// inside one body are left out of the long-range sum, as `neigh_modify exclude molecule/intra`
// leaves them out of a pair style. Their forces cancel in the body's net force and torque and
// their energy is a constant; in the body frame each pebble's share of them is constant, so it is
// computed once per body (kifmm::group_pair_sum, when a run starts or pebbles or strengths
// change) and subtracted, rotated into the lab frame, from every evaluation.
#include "kspace_kifmm.h"

#include "kifmm_rigid_bodies.h"

#include "atom.h"
#include "error.h"
#include "fix.h"
#include "modify.h"

#include <mpi.h>

using namespace LAMMPS_NS;

void KSpaceKIFMM::find_rigid_bodies()
{
  bodies.clear();
  for (int i = 0; i < modify->nfix; ++i)
    if (auto *b = dynamic_cast<KIFMMRigidBodies *>(modify->fix[i])) bodies.push_back(b);
}

// Before an evaluation (collective): the bodies' geometry is readable, and the per-pebble values
// are computed again where a pebble is new or its strength changed.
void KSpaceKIFMM::prepare_rigid_bodies()
{
  point_body.clear();
  if (bodies.empty()) return;
  const kifmm::KernelSpec kernel = engine->kernel();
  const KIFMMRigidBodies::BodyFunction pair_sums = [kernel](int n, const double *d, const double *s,
                                                            double *out) {
    std::vector<double> p(n), g(3 * (std::size_t) n), t(6 * (std::size_t) n);
    kifmm::group_pair_sum(kernel, n, d, s, p.data(), g.data(), t.data());
    for (int k = 0; k < n; ++k) {
      double *o = out + (std::size_t) KIFMMRigidBodies::nvalues * k;
      for (int c = 0; c < 3; ++c) o[c] = g[3 * k + c];
      o[3] = p[k];
      for (int c = 0; c < 6; ++c) o[4 + c] = t[6 * k + c];
    }
  };
  const KIFMMRigidBodies::Strength strength_fn = [this](int i) { return strength_of(i); };
  for (KIFMMRigidBodies *b : bodies) {
    std::string why;
    if (!b->bodies_ready(why))
      error->all(FLERR,
                 "kspace_style kifmm: cannot leave the pairs inside the clumps of fix {} out of "
                 "the long-range sum: {}",
                 b->bodies_id(), why);
    int stale = 0, any = 0;
    for (std::size_t k = 0; k < index.size() && !stale; ++k) {
      const double *v = b->body_values(index[k]);
      if (v && (v[KIFMMRigidBodies::value_valid] == 0.0 ||
                v[KIFMMRigidBodies::value_strength] != strength[k]))
        stale = 1;
    }
    MPI_Allreduce(&stale, &any, 1, MPI_INT, MPI_MAX, world);
    if (any) b->compute_body_values(strength_fn, pair_sums);
  }
  // the body of each point, its arm and the share of the pairs inside its body
  const std::size_t n = index.size();
  point_body.assign(n, 0);
  point_arm.assign(3 * n, 0.0);
  point_clump_weight.assign(n, 0.0);
  body_pairs.assign((std::size_t) KIFMMRigidBodies::nvalues * n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    const int i = index[k];
    for (KIFMMRigidBodies *b : bodies) {
      const double *v = b->body_values(i);
      if (!v) continue;
      double rot[9];
      b->body_frame(i, rot, &point_arm[3 * k]);
      point_body[k] = b->body_tag(i);
      point_clump_weight[k] = 1.0 / std::max(1.0, v[KIFMMRigidBodies::value_count]);
      // lab frame: gradient R g, potential, pair virial R T R^T
      double *o = &body_pairs[(std::size_t) KIFMMRigidBodies::nvalues * k];
      for (int a = 0; a < 3; ++a)
        o[a] = rot[3 * a] * v[0] + rot[3 * a + 1] * v[1] + rot[3 * a + 2] * v[2];
      o[3] = v[3];
      const double t[3][3] = {{v[4], v[7], v[8]}, {v[7], v[5], v[9]}, {v[8], v[9], v[6]}};
      double rt[3][3];
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) {
          rt[a][c] = 0.0;
          for (int m = 0; m < 3; ++m)
            for (int l = 0; l < 3; ++l) rt[a][c] += rot[3 * a + m] * t[m][l] * rot[3 * c + l];
        }
      o[4] = rt[0][0];
      o[5] = rt[1][1];
      o[6] = rt[2][2];
      o[7] = rt[0][1];
      o[8] = rt[0][2];
      o[9] = rt[1][2];
      break;
    }
  }
}

// After an evaluation: the pairs inside each body out of the gradients (and potentials).
void KSpaceKIFMM::subtract_body_pairs(bool potential)
{
  if (point_body.empty()) return;
  for (std::size_t k = 0; k < point_body.size(); ++k) {
    if (!point_body[k]) continue;
    const double *o = &body_pairs[(std::size_t) KIFMMRigidBodies::nvalues * k];
    for (int d = 0; d < 3; ++d) grad[3 * k + d] -= o[d];
    if (potential) pot[k] -= o[3];
  }
}
