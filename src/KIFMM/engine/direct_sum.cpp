#include "direct_sum.h"

#include "kernels.h"
#include "kifmm.h"

namespace kifmm {

void direct_sum(const KernelSpec &kernel, std::size_t n_src, const double *src_xyz, const double *src_q,
                std::size_t n_trg, const double *trg_xyz, double *pot, double *grad)
{
  if (kernel.type == KernelType::Yukawa)
    direct_sum_t(YukawaKernel{kernel.kappa}, n_src, src_xyz, src_q, n_trg, trg_xyz, pot, grad);
  else
    direct_sum_t(LaplaceKernel{}, n_src, src_xyz, src_q, n_trg, trg_xyz, pot, grad);
}

}    // namespace kifmm
