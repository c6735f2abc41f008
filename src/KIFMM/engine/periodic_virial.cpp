// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Per-point virial of the periodic sum (kifmm.h, periodic_point_virial).
#include "communicator.h"
#include "kifmm.h"

#include <algorithm>
#include <vector>

namespace kifmm {

void periodic_point_virial(Evaluator &ev, Communicator *comm, std::size_t n, const double *xyz,
                           const double *q, const double *grad, double prefactor, double *virial,
                           double *offset)
{
  std::vector<double> u(3 * n), psi(9 * n), moment(n), g(3 * n);
  ev.periodic_virial_fields(comm, n, xyz, q, u.data(), psi.data());
  // full (a, b) tensor per point, symmetrized at the end
  std::vector<double> T(9 * n);
  for (std::size_t k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) T[9 * k + 3 * a + b] = u[3 * k + a] * grad[3 * k + b] + psi[9 * k + 3 * a + b];
  const bool dist = comm && comm->size() > 1;
  for (int a = 0; a < 3; ++a) {
    for (std::size_t j = 0; j < n; ++j) moment[j] = q[j] * u[3 * j + a];
    std::fill(g.begin(), g.end(), 0.0);
    if (dist) ev.evaluate_distributed(*comm, n, xyz, moment.data(), nullptr, g.data());
    else if (n > 0) ev.evaluate(n, xyz, moment.data(), n, xyz, nullptr, g.data());
    for (std::size_t k = 0; k < n; ++k)
      for (int b = 0; b < 3; ++b) T[9 * k + 3 * a + b] -= g[3 * k + b];
  }
  const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  for (std::size_t k = 0; k < n; ++k) {
    const double c = 0.5 * prefactor * q[k];
    for (int m = 0; m < 6; ++m) {
      const int a = ab[m][0], b = ab[m][1];
      virial[6 * k + m] = c * 0.5 * (T[9 * k + 3 * a + b] + T[9 * k + 3 * b + a]);
    }
  }
  if (offset) std::copy(u.begin(), u.end(), offset);
}

void periodic_dipole_point_virial(Evaluator &ev, std::size_t n_src, const double *src_xyz, const double *src_q,
                                  const double *src_mu, std::size_t n_trg, const double *trg_xyz,
                                  const double *trg_q, const double *trg_mu, const double *grad,
                                  const double *hess, double prefactor, double *virial)
{
  std::vector<double> w(3 * n_src), u(3 * n_trg), psi(9 * n_trg), chi(18 * n_trg);
  ev.periodic_dipole_virial_fields(n_src, src_xyz, src_q, src_mu, n_trg, trg_xyz, w.data(), u.data(), psi.data(),
                                   chi.data());
  const int hs[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};    // (c, b) -> xx yy zz xy xz yz
  // D_k f: q_k d_b f + mu_k,c d_c d_b f of a field with gradient g and second derivatives h
  auto apply = [&](std::size_t k, const double *g, const double *h, int b) {
    double v = trg_q[k] * g[b];
    if (trg_mu)
      for (int c = 0; c < 3; ++c) v += trg_mu[3 * k + c] * h[hs[c][b]];
    return v;
  };
  std::vector<double> T(9 * n_trg);
  for (std::size_t k = 0; k < n_trg; ++k)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double v = u[3 * k + a] * apply(k, &grad[3 * k], &hess[6 * k], b) + trg_q[k] * psi[9 * k + 3 * a + b];
        if (trg_mu)
          for (int c = 0; c < 3; ++c) v += trg_mu[3 * k + c] * chi[18 * k + 6 * a + hs[c][b]];
        T[9 * k + 3 * a + b] = v;
      }
  std::vector<double> qa(n_src), ma(src_mu ? 3 * n_src : 0), g(3 * n_trg), h(6 * n_trg);
  for (int a = 0; a < 3; ++a) {
    for (std::size_t j = 0; j < n_src; ++j) {
      qa[j] = (src_q ? src_q[j] : 0.0) * w[3 * j + a];
      if (src_mu)
        for (int c = 0; c < 3; ++c) ma[3 * j + c] = src_mu[3 * j + c] * w[3 * j + a];
    }
    ev.evaluate_dipoles(n_src, src_xyz, qa.data(), src_mu ? ma.data() : nullptr, n_trg, trg_xyz, nullptr, g.data(),
                        h.data());
    for (std::size_t k = 0; k < n_trg; ++k)
      for (int b = 0; b < 3; ++b) T[9 * k + 3 * a + b] -= apply(k, &g[3 * k], &h[6 * k], b);
  }
  const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  for (std::size_t k = 0; k < n_trg; ++k)
    for (int m = 0; m < 6; ++m) virial[6 * k + m] = 0.5 * prefactor * T[9 * k + 3 * ab[m][0] + ab[m][1]];
}

}    // namespace kifmm
