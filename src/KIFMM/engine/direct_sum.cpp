// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "direct_sum.h"

#include "kernels.h"
#include "kifmm.h"

#include <cmath>

namespace kifmm {

void direct_sum(const KernelSpec &kernel, std::size_t n_src, const double *src_xyz, const double *src_q,
                std::size_t n_trg, const double *trg_xyz, double *pot, double *grad)
{
  if (kernel.type == KernelType::Yukawa)
    direct_sum_t(YukawaKernel{kernel.kappa}, n_src, src_xyz, src_q, n_trg, trg_xyz, pot, grad);
  else
    direct_sum_t(LaplaceKernel{}, n_src, src_xyz, src_q, n_trg, trg_xyz, pot, grad);
}

void direct_sum_dipoles(const KernelSpec &kernel, std::size_t n_src, const double *src_xyz, const double *src_q,
                        const double *src_mu, std::size_t n_trg, const double *trg_xyz, double *pot, double *grad,
                        double *hess)
{
  if (kernel.type == KernelType::Yukawa)
    direct_sum_dipoles_t(YukawaKernel{kernel.kappa}, n_src, src_xyz, src_q, src_mu, n_trg, trg_xyz, pot, grad, hess);
  else
    direct_sum_dipoles_t(LaplaceKernel{}, n_src, src_xyz, src_q, src_mu, n_trg, trg_xyz, pot, grad, hess);
}

namespace {
template <class K>
void group_pair_sum_t(const K &k, std::size_t n, const double *xyz, const double *q, double *pot,
                      double *grad, double *pair_virial)
{
  for (std::size_t i = 0; i < n; ++i) {
    double p = 0, g[3] = {0, 0, 0}, t[6] = {0, 0, 0, 0, 0, 0};
    for (std::size_t j = 0; j < n; ++j) {
      const double r[3] = {xyz[3 * i] - xyz[3 * j], xyz[3 * i + 1] - xyz[3 * j + 1],
                           xyz[3 * i + 2] - xyz[3 * j + 2]};
      const double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
      if (!(r2 > 0.0) || q[j] == 0.0) continue;
      double G, F;
      k.value_grad(r2, 1.0 / std::sqrt(r2), G, F);
      p += q[j] * G;
      const double qf = q[j] * F;    // dG/dx_i = F (x_i - x_j)
      for (int d = 0; d < 3; ++d) g[d] += qf * r[d];
      t[0] += qf * r[0] * r[0];
      t[1] += qf * r[1] * r[1];
      t[2] += qf * r[2] * r[2];
      t[3] += qf * r[0] * r[1];
      t[4] += qf * r[0] * r[2];
      t[5] += qf * r[1] * r[2];
    }
    if (pot) pot[i] = p;
    if (grad)
      for (int d = 0; d < 3; ++d) grad[3 * i + d] = g[d];
    if (pair_virial)
      for (int c = 0; c < 6; ++c) pair_virial[6 * i + c] = t[c];
  }
}
}    // namespace

void group_pair_sum(const KernelSpec &kernel, std::size_t n, const double *xyz, const double *q,
                    double *pot, double *grad, double *pair_virial)
{
  if (kernel.type == KernelType::Yukawa)
    group_pair_sum_t(YukawaKernel{kernel.kappa}, n, xyz, q, pot, grad, pair_virial);
  else
    group_pair_sum_t(LaplaceKernel{}, n, xyz, q, pot, grad, pair_virial);
}

}    // namespace kifmm
