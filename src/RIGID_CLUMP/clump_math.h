// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Small dense linear algebra for fix clump/rigid (no LAMMPS dependency): symmetric
// eigen-decomposition (cyclic Jacobi), best-fit rotation of two point sets (Horn's
// quaternion method), rigid-motion fit of velocities, quaternion helpers.
#pragma once

#include <array>
#include <vector>

namespace clump {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<std::array<double, 3>, 3>;

// Eigen-decomposition of the symmetric n x n matrix `a` (row-major, n <= 8), cyclic Jacobi.
// On return evals[k] are the eigenvalues (unsorted) and column k of evecs (evecs[i*n+k]) the
// matching unit eigenvector. Returns false if it did not converge.
bool jacobi_symmetric(int n, const double *a, double *evals, double *evecs);

// Rotation matrix of the unit quaternion q = (w, x, y, z).
Mat3 quat_to_matrix(const std::array<double, 4> &q);

// Best rotation R (proper, det = +1) minimizing sum_i |R p_i - q_i|^2 for two point sets that
// are already centred (sum p_i = sum q_i = 0), by Horn's quaternion method. Returns R and
// sets `rms` to the root-mean-square residual |R p_i - q_i| of the fit.
Mat3 best_rotation(const std::vector<Vec3> &p, const std::vector<Vec3> &q, double &rms);

// Rigid motion v_i ~ vc + omega x (x_i - c) fitted to point velocities by least squares
// (unit weights): returns vc (velocity of the point c) and omega. Rotation about an axis
// the points cannot resolve (collinear points, single point) is set to zero (pseudo-inverse).
void fit_rigid_motion(const std::vector<Vec3> &x, const std::vector<Vec3> &v, const Vec3 &c,
                      Vec3 &vc, Vec3 &omega);

Mat3 matmul(const Mat3 &a, const Mat3 &b);
Mat3 transpose(const Mat3 &a);
Vec3 matvec(const Mat3 &a, const Vec3 &x);

}    // namespace clump
