// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// PVFMM on the anchor benchmark's problem (anchors_problem.h), one MPI process. A setting is
// M:MAX_PTS (multipole order m, even; max points per leaf). Kernel: PVFMM's Laplace kernel with
// potential and gradient as one output of 4 values (its gradient kernel plus the potential; the
// far field through its Laplace potential kernel, as LaplaceKernel::gradient() does).
// Timed: PtFMM_CreateTree (tree) + SetupFMM (lists, per-tree setup) + PtFMM_Evaluate (passes),
// after one untimed cycle. Not timed: PtFMM::Initialize (operator precomputation; read from and
// saved to the directory of PVFMM_DIR when it is set), deleting the tree.
// Usage: anchors_pvfmm PROBLEM_FILE --settings M:MAX_PTS,... [--reps R] [--warmup W]
#include "anchors_problem.h"

#include <mpi.h>
#include <pvfmm.hpp>

namespace {

// 1/(4 pi) [1/r, (x_t - x_s)/r^3] q: potential and minus the gradient of the potential
struct laplace_pgrad_ {
  static const int FLOPS = 17;
  template <class Real> static Real ScaleFactor() { return 1 / (4 * sctl::const_pi<Real>()); }
  template <class VecType, int digits>
  static void uKerEval(VecType (&u)[4], const VecType (&r)[3], const VecType (&f)[1], const void *)
  {
    VecType r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    VecType rinv = sctl::approx_rsqrt<digits>(r2, r2 > VecType::Zero());
    VecType f_rinv = rinv * f[0];
    VecType f_rinv3 = rinv * rinv * f_rinv;
    u[0] = u[0] + f_rinv;
    u[1] = FMA(r[0], f_rinv3, u[1]);
    u[2] = FMA(r[1], f_rinv3, u[2]);
    u[3] = FMA(r[2], f_rinv3, u[3]);
  }
};
struct laplace_pgrad : public pvfmm::GenericKernel<laplace_pgrad_> {};

const pvfmm::Kernel<double> &potential_gradient_kernel()
{
  static pvfmm::Kernel<double> potn = pvfmm::BuildKernel<double, pvfmm::laplace_poten, pvfmm::laplace_dbl_poten>(
      "laplace", 3, std::pair<int, int>(1, 1));
  static pvfmm::Kernel<double> pgrad = pvfmm::BuildKernel<double, laplace_pgrad>(
      "laplace_pgrad", 3, std::pair<int, int>(1, 4), &potn, &potn, NULL, &potn, &potn, NULL, &potn, NULL);
  return pgrad;
}

}    // namespace

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  MPI_Comm comm = MPI_COMM_WORLD;
  const anchors::Args a = anchors::parse_args(argc, argv, "PROBLEM_FILE --settings M:MAX_PTS,... [--reps R] [--warmup W]");
  const anchors::Problem p = anchors::read_problem(a.file);
  const pvfmm::Kernel<double> &kernel = potential_gradient_kernel();
  const std::vector<double> coord(p.xyz), den(p.q);
  std::vector<double> grad(3 * p.n);
  for (const auto &s : a.settings) {
    const int m = (int) s.first, max_pts = (int) s.second;
    pvfmm::mem::MemoryManager mem_mgr(10000000);
    pvfmm::PtFMM<double> matrices(&mem_mgr);
    const anchors::Clock c0 = anchors::Clock::now();
    matrices.Initialize(m, comm, &kernel);
    const double t_pre = (anchors::Clock::now() - c0).wall;
    char setting[64];
    std::snprintf(setting, sizeof(setting), "m%d:max_pts%d", m, max_pts);
    for (int r = -a.warmup; r < a.reps; ++r) {
      std::vector<double> val;
      const anchors::Clock t0 = anchors::Clock::now();
      pvfmm::PtFMM_Tree<double> *tree = pvfmm::PtFMM_CreateTree(coord, den, coord, comm, max_pts, pvfmm::FreeSpace);
      tree->SetupFMM(&matrices);
      pvfmm::PtFMM_Evaluate(tree, val, p.n);
      const anchors::Clock t = anchors::Clock::now() - t0;
      int depth = 0;
      for (auto *node : tree->GetNodeList()) depth = std::max(depth, (int) node->Depth());
      delete tree;
      if (r < 0) continue;
      for (std::size_t i = 0; i < p.n; ++i)
        for (int d = 0; d < 3; ++d) grad[3 * i + d] = val[4 * i + 1 + d];
      // PVFMM: 1/(4 pi r) and minus the gradient
      const double err = anchors::gradient_error(p, grad.data(), -4 * M_PI);
      char extra[96];
      std::snprintf(extra, sizeof(extra), "precompute=%.3f", t_pre);
      anchors::print_row("pvfmm", p, setting, m, max_pts, depth, err, t, extra);
    }
  }
  MPI_Finalize();
  return 0;
}
