// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Independent reference for dielectric spheres (tests and bench/bench_dielectric_spheres): the
// axisymmetric multipole solution of two spheres in a uniform field along their line of
// centres (each sphere's exterior Legendre series re-expanded about the other, the interface
// conditions degree by degree, a dense solve; Jeffrey, Proc. R. Soc. A 335, 1973, for the
// method), converged in the number of degrees.
#pragma once

#include <Eigen/Dense>

#include <cmath>
#include <vector>

namespace kifmm_points {

// Two spheres of radius a (permittivity ratio eps) at z = +d/2 (sphere 1) and -d/2 (sphere 2),
// field E0 along z: the force on sphere 1 along z with `degrees` Legendre degrees per sphere.
// Potential (units of eps_out, 1/(4 pi r) per unit charge): -E0 z + sum_n A_n r1^-(n+1) P_n +
// B_n r2^-(n+1) P_n. About centre 1, r2^-(n+1) P_n(cos t2) = sum_m (-1)^m C(n+m, m) d^-(n+m+1)
// r1^m P_m(cos t1); about centre 2 the sign is (-1)^n. Interface of degree m for the local
// coefficients C_m: A_m = -m (eps - 1) / (m eps + m + 1) a^(2m+1) C_m. Force on sphere 1:
// F_z = -sum_m m C_m q_(m-1), q_n = int sigma r^n P_n dS = 4 pi A_n.
inline double two_sphere_force(double a, double d, double eps, double E0, int degrees)
{
  const int N = degrees;
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(2 * N, 2 * N);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * N);
  auto alpha = [&](int m) { return m * (eps - 1) / (m * eps + m + 1) * std::pow(a, 2 * m + 1); };
  auto coupling = [&](int n, int m) {    // C(n+m, m) / d^(n+m+1)
    return std::exp(std::lgamma(n + m + 1.0) - std::lgamma(n + 1.0) - std::lgamma(m + 1.0) - (n + m + 1) * std::log(d));
  };
  for (int m = 1; m <= N; ++m)
    for (int n = 1; n <= N; ++n) {
      M(m - 1, N + n - 1) += alpha(m) * (m % 2 ? -1.0 : 1.0) * coupling(n, m);    // A_m from B_n
      M(N + m - 1, n - 1) += alpha(m) * (n % 2 ? -1.0 : 1.0) * coupling(n, m);    // B_m from A_n
    }
  rhs[0] = rhs[N] = alpha(1) * E0;
  const Eigen::VectorXd x = M.partialPivLu().solve(rhs);
  double F = 0;
  for (int m = 2; m <= N; ++m) {
    double C = 0;
    for (int n = 1; n <= N; ++n) C += x[N + n - 1] * (m % 2 ? -1.0 : 1.0) * coupling(n, m);
    F -= m * C * 4 * std::acos(-1.0) * x[m - 2];
  }
  return F;
}

// The same for k spheres on the z axis (centres z, radii a, permittivity ratios eps), field E0
// along z: the forces along z (force[i]). The re-expansion about centre i of sphere j's
// r_j^-(n+1) P_n has the sign (-1)^m when z_i > z_j and (-1)^n when z_i < z_j.
inline std::vector<double> axial_spheres_forces(const std::vector<double> &z, const std::vector<double> &a,
                                                const std::vector<double> &eps, double E0, int degrees)
{
  const int k = (int) z.size(), N = degrees;
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(k * N, k * N);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k * N);
  auto alpha = [&](int i, int m) { return m * (eps[i] - 1) / (m * eps[i] + m + 1) * std::pow(a[i], 2 * m + 1); };
  // T(i, j, n, m): coefficient of r_i^m P_m about centre i of sphere j's degree-n term
  auto T = [&](int i, int j, int n, int m) {
    const double s = z[i] - z[j], d = std::fabs(s);
    const double c = std::exp(std::lgamma(n + m + 1.0) - std::lgamma(n + 1.0) - std::lgamma(m + 1.0) - (n + m + 1) * std::log(d));
    return ((s > 0 ? m : n) % 2 ? -1.0 : 1.0) * c;
  };
  for (int i = 0; i < k; ++i) {
    rhs[i * N] = alpha(i, 1) * E0;
    for (int j = 0; j < k; ++j)
      if (j != i)
        for (int m = 1; m <= N; ++m)
          for (int n = 1; n <= N; ++n) M(i * N + m - 1, j * N + n - 1) += alpha(i, m) * T(i, j, n, m);
  }
  const Eigen::VectorXd x = M.partialPivLu().solve(rhs);
  std::vector<double> force(k, 0.0);
  for (int i = 0; i < k; ++i)
    for (int m = 2; m <= N; ++m) {
      double C = 0;
      for (int j = 0; j < k; ++j)
        if (j != i)
          for (int n = 1; n <= N; ++n) C += x[j * N + n - 1] * T(i, j, n, m);
      force[i] -= m * C * 4 * std::acos(-1.0) * x[i * N + m - 2];
    }
  return force;
}

}    // namespace kifmm_points
