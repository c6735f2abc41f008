// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Rigid-body data of clumps of spherical pebbles (no LAMMPS dependency): for every clump its
// union-of-spheres mass, centre of mass and inertia (clump_union.h), and the velocity of its
// centre of mass and angular momentum fitted to the pebbles' velocities, written in the format
// of the infile keyword of fix rigid/small. Clumps that are rotated copies of one already
// integrated (same pebble radii, pebble centres equal after the best-fit rotation to 1e-4 of
// the smallest radius, RMS) reuse its result rotated (ShapeCache). fix clump/rigid gathers the
// pebbles of all clumps and calls write_bodies.
#pragma once

#include "clump_math.h"
#include "clump_union.h"

#include <map>
#include <string>
#include <vector>

namespace clump {

struct Pebble {
  long clump;    // clump (molecule) ID
  long tag;      // atom ID, names the pebble in error messages
  Vec3 x, v;     // unwrapped position, velocity
  double r;      // radius
};

struct Body {
  long id;
  double mass;
  Vec3 com;
  double itensor[6];    // about the COM, LAMMPS order xx yy zz yz xz xy
  Vec3 vcm, angmom;
};

// Inertia tensor in LAMMPS order (xx yy zz yz xz xy, off-diagonal entries the tensor's own)
// and as a matrix.
Mat3 itensor_to_matrix(const double t[6]);
void matrix_to_itensor(const Mat3 &m, double t[6]);

// Mass properties of pebble sets, integrated once per distinct shape.
class ShapeCache {
 public:
  ShapeCache(double density, double tol) : density_(density), tol_(tol) {}
  // mass, COM (lab frame) and inertia about it of pebbles s; rel_error: of the union volume
  void properties(const std::vector<Sphere> &s, double &mass, Vec3 &com, Mat3 &inertia,
                  double &rel_error);
  int computed() const { return computed_; }

 private:
  struct Shape {
    std::vector<Vec3> ref;    // pebble centres relative to their centroid
    double spread;            // sum of |ref|^2 (rotation invariant, quick pre-check)
    double mass, rel_error;
    Vec3 com;                 // relative to the centroid
    Mat3 inertia;             // about the COM
  };
  double density_, tol_;
  int computed_ = 0;
  std::map<std::vector<long long>, std::vector<Shape>> shapes_;    // by count and radii
};

// The bodies of all clumps of `pebbles` (any order; sorted by clump ID, then atom ID), or an
// error message naming the clump and its pebbles' atom IDs (empty bodies then).
struct BodiesResult {
  std::vector<Body> bodies;
  int shapes_integrated = 0;
  double worst_rel_error = 0.0;
  std::string error;
};
BodiesResult compute_bodies(std::vector<Pebble> pebbles, double density, double tol);

// fix rigid/small infile text of these bodies (header comments name the fix and density).
std::string bodies_file_text(const std::vector<Body> &bodies, const std::string &fix_id,
                             double density);

}    // namespace clump
