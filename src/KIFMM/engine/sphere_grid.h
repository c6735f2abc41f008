// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Quadrature grid on the unit sphere and real spherical harmonics up to a degree L, for the
// surface densities of dielectric spheres (dielectric_spheres.cpp).
//   nodes     : Gauss-Legendre in cos(theta) (L + 1 nodes) times the trapezoidal rule in phi
//               (2L + 2 nodes): 2 (L + 1)^2 nodes, exact for the product of two functions of
//               degree <= L (it integrates degree 2L + 1);
//   harmonics : Y_lm real and orthonormal on the unit sphere, index l^2 + l + m (m = -l .. l;
//               m > 0: cos(m phi), m < 0: sin(|m| phi));
//   transform : the coefficients of a function of degree <= L from its node values,
//               c_lm = sum_k w_k Y_lm(u_k) f_k (exact for such functions).
#pragma once

#include <cstddef>
#include <vector>

namespace kifmm {

inline int harmonic_count(int degree) { return (degree + 1) * (degree + 1); }
inline int harmonic_index(int l, int m) { return l * l + l + m; }

// Coefficients of the recurrences of the normalized associated Legendre functions up to a degree
struct HarmonicsTable {
  int degree = 0;
  std::vector<double> a, b, diag;    // a, b at harmonic_index(l, m); diag[m]: Pbar_m^m's factor
  explicit HarmonicsTable(int degree);
};
// y[harmonic_index(l, m)] = Y_lm(u) for l <= degree; u a unit vector.
void real_harmonics(const HarmonicsTable &t, const double u[3], double *y);

// Gauss-Legendre nodes and weights on [-1, 1] (n >= 1).
void gauss_legendre(int n, std::vector<double> &x, std::vector<double> &w);

struct SphereGrid {
  int degree = 0;
  std::size_t nodes = 0;
  std::vector<double> dir;          // unit vectors, 3 per node
  std::vector<double> weight;       // quadrature weights on the unit sphere (sum 4 pi)
  std::vector<double> harmonics;    // harmonics[k * nh + h] = Y_h(dir_k), nh = harmonic_count
  std::vector<double> transform;    // transform[h * nodes + k] = w_k Y_h(dir_k)
  HarmonicsTable table;
  explicit SphereGrid(int degree);
};

}    // namespace kifmm
