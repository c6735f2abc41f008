// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Induced point dipoles: the linear system mu_i / alpha_i - e_i(mu) = e0_i solved by conjugate
// gradients preconditioned with alpha (see kifmm.h). The operator's field part is the caller's
// evaluation (FMM or direct, one process or several), so the solver only combines vectors and
// global sums.
#include "kifmm.h"

#include <cmath>
#include <vector>

namespace kifmm {

namespace {
// y = mu / alpha - e(mu) at the polarizable points (zero elsewhere)
void apply_operator(std::size_t n, const double *alpha, const double *x,
                    const std::function<void(const double *, double *)> &field, std::vector<double> &e,
                    double *y)
{
  field(x, e.data());
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) y[3 * i + d] = alpha[i] > 0 ? x[3 * i + d] / alpha[i] - e[3 * i + d] : 0.0;
}
}    // namespace

PolarizationSolve solve_induced_dipoles(std::size_t n, const double *alpha, const double *e0,
                                        const std::function<void(const double *mu, double *e)> &field,
                                        const std::function<double(double)> &sum, double tolerance,
                                        int max_iterations, double *mu)
{
  PolarizationSolve out;
  const std::size_t m = 3 * n;
  std::vector<double> r(m), z(m), p(m), q(m), e(m);
  // the start guess only where a point is polarizable; is it zero everywhere?
  double start = 0, ref = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      double &x = mu[3 * i + d];
      if (!(alpha[i] > 0)) x = 0.0;
      start += x * x;
      ref += alpha[i] > 0 ? alpha[i] * e0[3 * i + d] * e0[3 * i + d] : 0.0;
    }
  start = sum(start);
  ref = sum(ref);
  if (!(ref > 0)) {    // no field at any polarizable point: no dipoles
    for (std::size_t k = 0; k < m; ++k) mu[k] = 0.0;
    out.converged = std::isfinite(ref);
    return out;
  }
  if (start > 0) {
    apply_operator(n, alpha, mu, field, e, q.data());
    ++out.evaluations;
    for (std::size_t k = 0; k < m; ++k) r[k] = alpha[k / 3] > 0 ? e0[k] - q[k] : 0.0;
  } else {
    for (std::size_t k = 0; k < m; ++k) r[k] = alpha[k / 3] > 0 ? e0[k] : 0.0;
  }
  auto precondition = [&](double &rz) {
    double local = 0;
    for (std::size_t k = 0; k < m; ++k) {
      z[k] = alpha[k / 3] > 0 ? alpha[k / 3] * r[k] : 0.0;
      local += r[k] * z[k];
    }
    rz = sum(local);
  };
  double rz = 0;
  precondition(rz);
  out.residual = std::sqrt(rz / ref);
  if (out.residual <= tolerance) {
    out.converged = true;
    return out;
  }
  p = z;
  while (out.iterations < max_iterations) {
    apply_operator(n, alpha, p.data(), field, e, q.data());
    ++out.evaluations;
    double local = 0;
    for (std::size_t k = 0; k < m; ++k) local += p[k] * q[k];
    const double pq = sum(local);
    if (!(pq > 0)) {
      out.indefinite = std::isfinite(pq);
      return out;
    }
    const double a = rz / pq;
    for (std::size_t k = 0; k < m; ++k) {
      mu[k] += a * p[k];
      r[k] -= a * q[k];
    }
    ++out.iterations;
    double rz_next = 0;
    precondition(rz_next);
    out.residual = std::sqrt(rz_next / ref);
    if (!std::isfinite(out.residual)) return out;
    if (out.residual <= tolerance) {
      out.converged = true;
      return out;
    }
    const double beta = rz_next / rz;
    for (std::size_t k = 0; k < m; ++k) p[k] = z[k] + beta * p[k];
    rz = rz_next;
  }
  return out;
}

}    // namespace kifmm
