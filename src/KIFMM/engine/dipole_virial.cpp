// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Per-point virial of charges and dipoles (kifmm.h: dipole_point_virial, open boundaries;
// periodic_dipole_point_virial). With D_k = q_k d_b + mu_k,c d_c d_b (the force operator of
// point k) and r = x_k - y_j, sum_j r_a D_k Phi_j = u_a D_k phi - D_k phi^(a) (+ the image
// offsets when periodic), u = x_k - c, phi^(a) the potential of the strengths (q_j, mu_j)
// times (y_j - c)_a: three more dipole evaluations.
#include "kifmm.h"

#include <vector>

namespace kifmm {

namespace {

const int hs[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};    // (c, b) -> xx yy zz xy xz yz

// D_k f (component b) of a field with gradient g and second derivatives h at target k
double apply(const double *q, const double *mu, std::size_t k, const double *g, const double *h, int b)
{
  double v = q[k] * g[b];
  if (mu)
    for (int c = 0; c < 3; ++c) v += mu[3 * k + c] * h[hs[c][b]];
  return v;
}

// T[9k + 3a + b] -= D_k phi^(a) for a = 0..2 (strengths times w_a); with comm distributed (the
// sources are the targets, this rank's points)
void subtract_moment_fields(Evaluator &ev, Communicator *comm, std::size_t n_src, const double *src_xyz,
                            const double *src_q, const double *src_mu, const std::vector<double> &w, std::size_t n_trg,
                            const double *trg_xyz, const double *trg_q, const double *trg_mu, std::vector<double> &T)
{
  std::vector<double> qa(n_src), ma(src_mu ? 3 * n_src : 0), g(3 * n_trg), h(6 * n_trg);
  for (int a = 0; a < 3; ++a) {
    for (std::size_t j = 0; j < n_src; ++j) {
      qa[j] = (src_q ? src_q[j] : 0.0) * w[3 * j + a];
      if (src_mu)
        for (int c = 0; c < 3; ++c) ma[3 * j + c] = src_mu[3 * j + c] * w[3 * j + a];
    }
    if (comm)
      ev.evaluate_dipoles_distributed(*comm, n_src, src_xyz, qa.data(), src_mu ? ma.data() : nullptr, nullptr,
                                      g.data(), h.data());
    else
      ev.evaluate_dipoles(n_src, src_xyz, qa.data(), src_mu ? ma.data() : nullptr, n_trg, trg_xyz, nullptr,
                          g.data(), h.data());
    for (std::size_t k = 0; k < n_trg; ++k)
      for (int b = 0; b < 3; ++b) T[9 * k + 3 * a + b] -= apply(trg_q, trg_mu, k, &g[3 * k], &h[6 * k], b);
  }
}

void to_virial(const std::vector<double> &T, std::size_t n_trg, double prefactor, double *virial)
{
  const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  for (std::size_t k = 0; k < n_trg; ++k)
    for (int m = 0; m < 6; ++m) virial[6 * k + m] = 0.5 * prefactor * T[9 * k + 3 * ab[m][0] + ab[m][1]];
}

}    // namespace

void dipole_point_virial(Evaluator &ev, std::size_t n_src, const double *src_xyz, const double *src_q,
                         const double *src_mu, std::size_t n_trg, const double *trg_xyz, const double *trg_q,
                         const double *trg_mu, const double *grad, const double *hess, double prefactor,
                         double *virial, const double center[3])
{
  std::vector<double> w(3 * n_src), T(9 * n_trg);
  for (std::size_t j = 0; j < n_src; ++j)
    for (int a = 0; a < 3; ++a) w[3 * j + a] = src_xyz[3 * j + a] - center[a];
  for (std::size_t k = 0; k < n_trg; ++k)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        T[9 * k + 3 * a + b] = (trg_xyz[3 * k + a] - center[a]) * apply(trg_q, trg_mu, k, &grad[3 * k], &hess[6 * k], b);
  subtract_moment_fields(ev, nullptr, n_src, src_xyz, src_q, src_mu, w, n_trg, trg_xyz, trg_q, trg_mu, T);
  to_virial(T, n_trg, prefactor, virial);
}

void dipole_point_virial(Evaluator &ev, Communicator &comm, std::size_t n, const double *xyz, const double *q,
                         const double *mu, const double *grad, const double *hess, double prefactor, double *virial,
                         const double center[3])
{
  std::vector<double> w(3 * n), T(9 * n);
  for (std::size_t j = 0; j < n; ++j)
    for (int a = 0; a < 3; ++a) w[3 * j + a] = xyz[3 * j + a] - center[a];
  for (std::size_t k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) T[9 * k + 3 * a + b] = w[3 * k + a] * apply(q, mu, k, &grad[3 * k], &hess[6 * k], b);
  subtract_moment_fields(ev, &comm, n, xyz, q, mu, w, n, xyz, q, mu, T);
  to_virial(T, n, prefactor, virial);
}

namespace {

// periodic_dipole_point_virial, with comm distributed (sources = targets, this rank's points)
void periodic_virial(Evaluator &ev, Communicator *comm, std::size_t n_src, const double *src_xyz,
                     const double *src_q, const double *src_mu, std::size_t n_trg, const double *trg_xyz,
                     const double *trg_q, const double *trg_mu, const double *grad, const double *hess,
                     double prefactor, double *virial)
{
  std::vector<double> w(3 * n_src), u(3 * n_trg), psi(9 * n_trg), chi(18 * n_trg), T(9 * n_trg);
  ev.periodic_dipole_virial_fields(comm, n_src, src_xyz, src_q, src_mu, n_trg, trg_xyz, w.data(), u.data(),
                                   psi.data(), chi.data());
  for (std::size_t k = 0; k < n_trg; ++k)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double v = u[3 * k + a] * apply(trg_q, trg_mu, k, &grad[3 * k], &hess[6 * k], b) +
            trg_q[k] * psi[9 * k + 3 * a + b];
        if (trg_mu)
          for (int c = 0; c < 3; ++c) v += trg_mu[3 * k + c] * chi[18 * k + 6 * a + hs[c][b]];
        T[9 * k + 3 * a + b] = v;
      }
  subtract_moment_fields(ev, comm, n_src, src_xyz, src_q, src_mu, w, n_trg, trg_xyz, trg_q, trg_mu, T);
  to_virial(T, n_trg, prefactor, virial);
}

}    // namespace

void periodic_dipole_point_virial(Evaluator &ev, std::size_t n_src, const double *src_xyz, const double *src_q,
                                  const double *src_mu, std::size_t n_trg, const double *trg_xyz,
                                  const double *trg_q, const double *trg_mu, const double *grad,
                                  const double *hess, double prefactor, double *virial)
{
  periodic_virial(ev, nullptr, n_src, src_xyz, src_q, src_mu, n_trg, trg_xyz, trg_q, trg_mu, grad, hess, prefactor,
                  virial);
}

void periodic_dipole_point_virial(Evaluator &ev, Communicator &comm, std::size_t n, const double *xyz,
                                  const double *q, const double *mu, const double *grad, const double *hess,
                                  double prefactor, double *virial)
{
  periodic_virial(ev, &comm, n, xyz, q, mu, n, xyz, q, mu, grad, hess, prefactor, virial);
}

}    // namespace kifmm
