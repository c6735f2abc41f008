// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "clump_bodies.h"

#include "clump_template.h"
#include "clump_union.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace clump {

Mat3 itensor_to_matrix(const double t[6])
{
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

void ShapeCache::properties(const std::vector<Sphere> &s, double &mass, Vec3 &com, Mat3 &inertia,
                            double &rel_error)
{
  const std::size_t np = s.size();
  double rmin = 1e300, rmax = 0.0;
  for (const Sphere &p : s) {
    rmin = std::min(rmin, p.r);
    rmax = std::max(rmax, p.r);
  }
  // shapes are keyed by their pebble count and radii (relative to the largest, to 1e-9)
  std::vector<long long> key = {(long long) np};
  for (const Sphere &p : s) key.push_back(std::llround(p.r / rmax * 1e9));
  Vec3 g{0, 0, 0};
  for (const Sphere &p : s)
    for (int d = 0; d < 3; ++d) g[d] += p.x[d] / (double) np;
  std::vector<Vec3> rel(np);
  double spread = 0.0;
  for (std::size_t k = 0; k < np; ++k)
    for (int d = 0; d < 3; ++d) {
      rel[k][d] = s[k].x[d] - g[d];
      spread += rel[k][d] * rel[k][d];
    }
  const double match = 1e-4 * rmin;    // RMS distance for "same shape"

  auto &candidates = shapes_[key];
  for (const Shape &sh : candidates) {
    // |sqrt(spread) - sqrt(sh.spread)| <= RMS-fit residual * sqrt(np)
    if (std::fabs(std::sqrt(spread) - std::sqrt(sh.spread)) > match * std::sqrt((double) np)) continue;
    double rms;
    const Mat3 rot = best_rotation(sh.ref, rel, rms);
    if (rms > match) continue;
    const Vec3 c = matvec(rot, sh.com);
    for (int d = 0; d < 3; ++d) com[d] = g[d] + c[d];
    inertia = matmul(matmul(rot, sh.inertia), transpose(rot));
    mass = sh.mass;
    rel_error = sh.rel_error;
    return;
  }
  std::vector<Sphere> local(s);
  for (std::size_t k = 0; k < np; ++k)
    for (int d = 0; d < 3; ++d) local[k].x[d] = rel[k][d];
  const MassProperties p = union_mass_properties(local, density_, tol_);
  Shape sh;
  sh.ref = rel;
  sh.spread = spread;
  sh.mass = p.mass;
  sh.rel_error = p.rel_error;
  sh.com = {p.com[0], p.com[1], p.com[2]};
  sh.inertia = itensor_to_matrix(p.itensor);
  candidates.push_back(sh);
  ++computed_;
  mass = sh.mass;
  rel_error = sh.rel_error;
  for (int d = 0; d < 3; ++d) com[d] = g[d] + sh.com[d];
  inertia = sh.inertia;
}

BodiesResult compute_bodies(std::vector<Pebble> pebbles, double density, double tol)
{
  std::sort(pebbles.begin(), pebbles.end(), [](const Pebble &a, const Pebble &b) {
    return a.clump != b.clump ? a.clump < b.clump : a.tag < b.tag;
  });
  BodiesResult out;
  ShapeCache shapes(density, tol);
  for (std::size_t start = 0; start < pebbles.size();) {
    std::size_t end = start;
    const long id = pebbles[start].clump;
    while (end < pebbles.size() && pebbles[end].clump == id) ++end;
    const std::size_t np = end - start;
    std::vector<Sphere> s(np);
    std::vector<Vec3> x(np), v(np);
    std::vector<long> labels(np);
    for (std::size_t k = 0; k < np; ++k) {
      const Pebble &p = pebbles[start + k];
      labels[k] = p.tag;
      for (int d = 0; d < 3; ++d) s[k].x[d] = p.x[d];
      s[k].r = p.r;
      x[k] = p.x;
      v[k] = p.v;
    }
    const std::string why = check_pebbles(s, labels);
    if (!why.empty()) {
      out.bodies.clear();
      out.error = "clump (molecule ID) " + std::to_string(id) + ": " + why + " (atom IDs)";
      return out;
    }
    Body b;
    b.id = id;
    Mat3 inertia;
    double rel_error;
    shapes.properties(s, b.mass, b.com, inertia, rel_error);
    out.worst_rel_error = std::max(out.worst_rel_error, rel_error);
    // rigid motion of the pebbles: velocity of the COM and angular momentum L = I omega
    Vec3 omega;
    fit_rigid_motion(x, v, b.com, b.vcm, omega);
    b.angmom = matvec(inertia, omega);
    matrix_to_itensor(inertia, b.itensor);
    out.bodies.push_back(b);
    start = end;
  }
  out.shapes_integrated = shapes.computed();
  return out;
}

std::string bodies_file_text(const std::vector<Body> &bodies, const std::string &fix_id,
                             double density)
{
  std::ostringstream out;
  out.precision(17);
  out << "# fix clump/rigid " << fix_id << ": union-of-spheres mass properties at density "
      << density << "\n"
      << "# id mass xcm ycm zcm ixx iyy izz ixy ixz iyz vxcm vycm vzcm lx ly lz ixcm iycm izcm\n"
      << bodies.size() << "\n";
  for (const Body &b : bodies) {
    const double *it = b.itensor;
    out << b.id << ' ' << b.mass << ' ' << b.com[0] << ' ' << b.com[1] << ' ' << b.com[2] << ' '
        << it[0] << ' ' << it[1] << ' ' << it[2] << ' ' << it[5] << ' ' << it[4] << ' ' << it[3]
        << ' ' << b.vcm[0] << ' ' << b.vcm[1] << ' ' << b.vcm[2] << ' ' << b.angmom[0] << ' '
        << b.angmom[1] << ' ' << b.angmom[2] << " 0 0 0\n";
  }
  return out.str();
}

}    // namespace clump
