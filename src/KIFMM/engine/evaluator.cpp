// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// make_evaluator: runtime switch from KernelSpec to the templated core (fmm_core.h).
#include "fmm_core.h"
#include "kernels.h"
#include "kifmm.h"

namespace kifmm {

std::unique_ptr<Evaluator> make_evaluator(const KernelSpec &kernel, const Options &options)
{
  if (kernel.type == KernelType::Yukawa)
    return std::make_unique<FmmEvaluator<YukawaKernel>>(YukawaKernel{kernel.kappa}, kernel, options);
  return std::make_unique<FmmEvaluator<LaplaceKernel>>(LaplaceKernel{}, kernel, options);
}

}    // namespace kifmm
