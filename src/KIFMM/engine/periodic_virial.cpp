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

}    // namespace kifmm
