// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "operators.h"

#include "m2l_fft.h"
#include "surface.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <cmath>

namespace kifmm {

using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

std::size_t OperatorSet::bytes() const
{
  std::size_t b = uc2e_a.size() + uc2e_b.size() + dc2e_a.size() + dc2e_b.size() + m2l_hat.size();
  for (int i = 0; i < 8; ++i) b += m2m[i].size() + l2l[i].size();
  return b * sizeof(double);
}

double pinv_relative_cutoff(int) { return 1e-15; }

void matvec(const double *M, int rows, int cols, const double *x, double *y, double alpha, bool accumulate)
{
  Eigen::Map<const RowMat> A(M, rows, cols);
  Eigen::Map<const Eigen::VectorXd> vx(x, cols);
  Eigen::Map<Eigen::VectorXd> vy(y, rows);
  if (accumulate) vy.noalias() += alpha * (A * vx);
  else vy.noalias() = alpha * (A * vx);
}

void apply_pinv(const std::vector<double> &A, const std::vector<double> &B, int nsurf, int rank,
                const double *check, double *equiv, double alpha, double *scratch)
{
  matvec(B.data(), rank, nsurf, check, scratch, 1.0, false);
  matvec(A.data(), nsurf, rank, scratch, equiv, alpha, false);
}

void matmat(const double *M, int rows, int cols, const double *X, int m, double *Y, double alpha, bool accumulate)
{
  Eigen::Map<const RowMat> A(M, rows, cols);
  Eigen::Map<const Eigen::MatrixXd> x(X, cols, m);
  Eigen::Map<Eigen::MatrixXd> y(Y, rows, m);
  if (accumulate) y.noalias() += alpha * (A * x);
  else y.noalias() = alpha * (A * x);
}

void apply_pinv_batch(const std::vector<double> &A, const std::vector<double> &B, int nsurf, int rank,
                      const double *check, int m, double *equiv, double alpha)
{
  Eigen::Map<const RowMat> a(A.data(), nsurf, rank), b(B.data(), rank, nsurf);
  Eigen::Map<const Eigen::MatrixXd> c(check, nsurf, m);
  Eigen::Map<Eigen::MatrixXd> e(equiv, nsurf, m);
  const Eigen::MatrixXd tmp = b * c;
  e.noalias() = alpha * (a * tmp);
}

namespace {

RowMat kernel_matrix(const UnitKernel &k, const SurfacePoints &trg, const SurfacePoints &src)
{
  RowMat M(trg.size(), src.size());
  for (int i = 0; i < trg.size(); ++i)
    for (int j = 0; j < src.size(); ++j) {
      const double dx = trg.x[i] - src.x[j], dy = trg.y[i] - src.y[j], dz = trg.z[i] - src.z[j];
      M(i, j) = k.g(dx * dx + dy * dy + dz * dz);
    }
  return M;
}

std::vector<double> to_vec(const RowMat &M) { return std::vector<double>(M.data(), M.data() + M.size()); }

SurfacePoints child_surface(const SurfacePoints &unit_alpha, int oct, const double shape[3])
{
  // surface of child octant oct of the unit box, in parent unit coordinates
  const double c[3] = {((oct & 1) ? 0.5 : -0.5) * shape[0], ((oct & 2) ? 0.5 : -0.5) * shape[1],
                       ((oct & 4) ? 0.5 : -0.5) * shape[2]};
  SurfacePoints s;
  box_surface(unit_alpha, c, 0.5, s);
  return s;
}

}    // namespace

std::shared_ptr<OperatorSet> compute_operators(const UnitKernel &k, int p)
{
  auto op = std::make_shared<OperatorSet>();
  op->p = p;
  op->id = k.id;
  const int ns = surface_size(p);
  op->nsurf = ns;
  // the unit box (half-widths k.shape): surfaces scaled per axis
  const SurfacePoints inner = shaped_surface(p, kRadiusInner, k.shape),
                      outer = shaped_surface(p, kRadiusOuter, k.shape);

  // upward check (outer) <- upward equivalent (inner); the downward matrix is its transpose
  // for a symmetric kernel: K(inner, outer) = K(outer, inner)^T.
  const RowMat M = kernel_matrix(k, outer, inner);
  Eigen::BDCSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd S = svd.singularValues();
  const double cut = S(0) * pinv_relative_cutoff(p);
  int rank = 0;
  while (rank < S.size() && S(rank) > cut) ++rank;
  op->rank = rank;
  const Eigen::MatrixXd U = svd.matrixU().leftCols(rank), V = svd.matrixV().leftCols(rank);
  const Eigen::VectorXd Sinv = S.head(rank).cwiseInverse();
  // pinv(M) = V S^-1 U^T ; pinv(M^T) = U S^-1 V^T
  const RowMat UA = V * Sinv.asDiagonal(), UB = U.transpose();
  const RowMat DA = U * Sinv.asDiagonal(), DB = V.transpose();
  op->uc2e_a = to_vec(UA);
  op->uc2e_b = to_vec(UB);
  op->dc2e_a = to_vec(DA);
  op->dc2e_b = to_vec(DB);

  for (int oct = 0; oct < 8; ++oct) {
    // M2M: parent outer check <- child inner equivalent, then parent pseudo-inverse
    const RowMat Kc = kernel_matrix(k, outer, child_surface(inner, oct, k.shape));
    const RowMat m2m = UA * (UB * Kc);
    op->m2m[oct] = to_vec(m2m);
    // L2L: child inner check <- parent outer equivalent (to the child's check potential)
    op->l2l[oct] = to_vec(kernel_matrix(k, child_surface(inner, oct, k.shape), outer));
  }
  m2l_kernel_transforms(k, p, op->m2l_hat, op->nfreq);
  return op;
}

}    // namespace kifmm
