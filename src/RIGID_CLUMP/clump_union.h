// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Mass properties of a union of (possibly overlapping) spheres at uniform density.
// No LAMMPS dependency; used by fix clump/rigid and tested on its own.
//
// Method ("power-diagram pieces, exact radial integrals, adaptive angular quadrature"):
//   The union of balls B_i is the disjoint union of the pieces B_i ∩ P_i, where P_i is the
//   power (Laguerre) cell of ball i: the points x with |x - c_i|^2 - r_i^2 <= |x - c_j|^2 - r_j^2
//   for all j. Only balls that overlap B_i bound P_i inside B_i, each by one radical plane. On a
//   ray from c_i in direction w the piece is one segment [lo(w), hi(w)] (intersection of the
//   half-lines cut by the planes with [0, r_i]), so the radial integrals of the moment
//   integrands (1, x, x x^T) are polynomials in lo and hi, evaluated exactly. The remaining
//   integral over the directions w is done on the six faces of a cube (gnomonic map) by
//   tensor-product 4 x 4 Gauss-Legendre rules with global adaptive refinement: the cell with
//   the largest |rule(cell) - sum of rule(children)| is split until the sum of these
//   estimates is below the tolerance. The angular integrands are continuous (kinks only where
//   the segment end switches from the sphere to a plane or between planes: no square-root
//   edges, no missed slivers), so the estimate is reliable; caps smaller than a cell, which
//   its Gauss points could miss, add their whole volume to that cell's estimate.
//   The accepted value is the sum of the children's rules, much more accurate than the
//   estimate, so the reported error is an upper estimate (tests: two overlapping spheres
//   against the exact lens/union formulas).
#pragma once

#include <array>
#include <vector>

namespace clump {

struct Sphere {
  double x[3];
  double r;
};

// Volume integrals of the union about the coordinate origin.
struct UnionMoments {
  double volume = 0.0;                  // integral of 1
  double first[3] = {0.0, 0.0, 0.0};    // integrals of x, y, z
  // integrals of xx, yy, zz, yz, xz, xy
  double second[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  double error_volume = 0.0;    // estimated absolute error of `volume`
  long cells = 0;               // accepted quadrature cells
};

// rel_tol: requested relative accuracy of the volume (and, scaled, of the second moments).
UnionMoments union_moments(const std::vector<Sphere> &spheres, double rel_tol);

// Mass, centre of mass and inertia tensor about the centre of mass at density `rho`.
// itensor in LAMMPS order: Ixx, Iyy, Izz, Iyz, Ixz, Ixy with the off-diagonal elements of
// the tensor (Iyz = -rho * integral of (y - yc)(z - zc)), as fix rigid/small's infile and
// LAMMPS molecule files use them.
struct MassProperties {
  double volume = 0.0;
  double mass = 0.0;
  double com[3] = {0.0, 0.0, 0.0};
  double itensor[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  double rel_error = 0.0;    // estimated relative error of the volume (and so the mass)
  long cells = 0;
};

MassProperties union_mass_properties(const std::vector<Sphere> &spheres, double rho,
                                     double rel_tol);

// Index pairs (i, j), i < j, of spheres whose centres coincide within rel_tol * min(r_i, r_j)
// (duplicate pebbles), found with a cell list.
std::vector<std::array<int, 2>> duplicate_spheres(const std::vector<Sphere> &spheres,
                                                  double rel_tol = 1e-6);

}    // namespace clump
