// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Restarted GMRES (Saad and Schultz, SIAM J. Sci. Stat. Comput. 7, 1986) for a real linear
// system A x = b whose operator is a callback (e.g. an FMM evaluation): Arnoldi with modified
// Gram-Schmidt, Givens rotations, a restart every `restart` steps; stops when
// |b - A x| <= tolerance |b|. x holds the start guess on entry.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

namespace kifmm {

struct GmresResult {
  int iterations = 0;         // Arnoldi steps (operator applications besides the residuals)
  int applications = 0;       // calls of the operator in all
  double residual = 0;        // |b - A x| / |b| of the returned x (recomputed at the end)
  bool converged = false;
};

inline GmresResult gmres(std::size_t n, const std::function<void(const double *, double *)> &apply,
                         const double *b, double *x, double tolerance, int max_iterations, int restart = 40)
{
  GmresResult out;
  auto norm = [n](const double *v) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += v[i] * v[i];
    return std::sqrt(s);
  };
  const double bnorm = norm(b);
  if (!(bnorm > 0)) {
    for (std::size_t i = 0; i < n; ++i) x[i] = 0.0;
    out.converged = std::isfinite(bnorm);
    return out;
  }
  std::vector<double> r(n), w(n);
  std::vector<std::vector<double>> v;
  const int m = restart;
  std::vector<double> h((m + 1) * m), cs(m), sn(m), g(m + 1), y(m);
  auto residual = [&]() {
    apply(x, w.data());
    ++out.applications;
    for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - w[i];
    return norm(r.data());
  };
  double beta = residual();
  out.residual = beta / bnorm;
  while (out.residual > tolerance && out.iterations < max_iterations && std::isfinite(beta)) {
    v.assign(1, std::vector<double>(n));
    for (std::size_t i = 0; i < n; ++i) v[0][i] = r[i] / beta;
    std::fill(g.begin(), g.end(), 0.0);
    g[0] = beta;
    int k = 0;
    for (; k < m && out.iterations < max_iterations; ++k) {
      apply(v[k].data(), w.data());
      ++out.applications;
      ++out.iterations;
      for (int j = 0; j <= k; ++j) {
        double d = 0;
        for (std::size_t i = 0; i < n; ++i) d += w[i] * v[j][i];
        h[j * m + k] = d;
        for (std::size_t i = 0; i < n; ++i) w[i] -= d * v[j][i];
      }
      const double hn = norm(w.data());
      h[(k + 1) * m + k] = hn;
      for (int j = 0; j < k; ++j) {    // earlier rotations on the new column
        const double a = h[j * m + k], c = h[(j + 1) * m + k];
        h[j * m + k] = cs[j] * a + sn[j] * c;
        h[(j + 1) * m + k] = -sn[j] * a + cs[j] * c;
      }
      const double a = h[k * m + k], c = h[(k + 1) * m + k], rr = std::hypot(a, c);
      cs[k] = rr > 0 ? a / rr : 1.0;
      sn[k] = rr > 0 ? c / rr : 0.0;
      h[k * m + k] = rr;
      h[(k + 1) * m + k] = 0.0;
      g[k + 1] = -sn[k] * g[k];
      g[k] = cs[k] * g[k];
      const bool done = std::fabs(g[k + 1]) <= tolerance * bnorm || !(hn > 0);
      if (!done) {
        v.emplace_back(n);
        for (std::size_t i = 0; i < n; ++i) v[k + 1][i] = w[i] / hn;
      }
      if (done) {
        ++k;
        break;
      }
    }
    for (int j = k - 1; j >= 0; --j) {    // back substitution
      double s = g[j];
      for (int l = j + 1; l < k; ++l) s -= h[j * m + l] * y[l];
      y[j] = s / h[j * m + j];
    }
    for (int j = 0; j < k; ++j)
      for (std::size_t i = 0; i < n; ++i) x[i] += y[j] * v[j][i];
    beta = residual();
    out.residual = beta / bnorm;
  }
  out.converged = out.residual <= tolerance;
  return out;
}

}    // namespace kifmm
