// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Equivalent / check surfaces: the boundary points of a regular p x p x p grid on a cube.
// Unit box: center 0, half-width 1; the surface of radius factor alpha has its points at
// alpha * (-1 + 2 i/(p-1)) per axis, i = 0..p-1, keeping those with an index on the boundary
// (6(p-1)^2 + 2 points). Radii follow Ying-Biros-Zorin / exafmm-t:
//   upward   equivalent 1.05, check 2.95;   downward equivalent 2.95, check 1.05.
// The M2L maps an upward-equivalent surface (1.05) to a downward-check surface (1.05): both
// lie on the same regular lattice, so M2L is a convolution (m2l_fft.h).
#pragma once

#include <vector>

namespace kifmm {

constexpr double kRadiusInner = 1.05;
constexpr double kRadiusOuter = 2.95;

inline int surface_size(int p) { return p == 1 ? 1 : 6 * (p - 1) * (p - 1) + 2; }

// Structure of arrays, so surfaces can be used as P2P sources or targets directly.
struct SurfacePoints {
  std::vector<double> x, y, z;
  int size() const { return (int) x.size(); }
};

// Surface of the unit box scaled by alpha (points in a fixed order shared by all users).
SurfacePoints unit_surface(int p, double alpha);

// Surface of a rectangular unit box (half-widths shape[d], largest 1): unit_surface scaled per
// axis. The surfaces of the cells of a rectangular root (RootBox::shape).
SurfacePoints shaped_surface(int p, double alpha, const double shape[3]);

// Same surface for a box of center c and half-width h: c + h * unit_surface(p, alpha).
void box_surface(const SurfacePoints &unit, const double c[3], double h, SurfacePoints &out);

// Lattice index (i,j,k) in [0,p)^3 of each surface point, 3 ints per point.
std::vector<int> surface_lattice(int p);

}    // namespace kifmm
