// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "periodic_grid.h"

#include "ewald_split.h"
#include "slab_ewald.h"
#include "m2l_fft.h"
#include "surface.h"

#include <fftw3.h>

#include <algorithm>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

namespace kifmm {

using namespace ewald;

GridKernel::~GridKernel()
{
  std::lock_guard<std::mutex> lock(fftw_mutex());
  if (plan_fwd) fftw_destroy_plan((fftw_plan) plan_fwd);
  if (plan_bwd) fftw_destroy_plan((fftw_plan) plan_bwd);
}

std::complex<double> *grid_alloc(std::size_t n)
{
  auto *z = reinterpret_cast<std::complex<double> *>(fftw_alloc_complex(n));
  if (!z) throw std::bad_alloc();
  return z;
}

void grid_free(std::complex<double> *z)
{
  if (z) fftw_free(reinterpret_cast<fftw_complex *>(z));
}

void grid_convolve(const GridKernel &g, std::complex<double> *z, int f0, int f1)
{
  const std::size_t kc = g.slots(), nf = g.nfreq;
  for (int f = f0; f < f1; f += 16) {
    auto *col = reinterpret_cast<fftw_complex *>(z + f);
    fftw_execute_dft((fftw_plan) g.plan_fwd, col, col);
    for (std::size_t w = 0; w < kc; ++w) {
      std::complex<double> *y = z + w * nf + f;
      const std::complex<double> *h = g.hat.data() + w * nf + f;
      for (int i = 0; i < 16; ++i) y[i] *= h[i];
    }
    fftw_execute_dft((fftw_plan) g.plan_bwd, col, col);
  }
}

namespace {

// Mirror symmetry of the kernel tables: the lattice sums are even in each coordinate (orthogonal
// lattice, symmetric image and reciprocal sets), and class D with offset i mirrors to class -D
// with offset 2(p - 1) - i, whose excluded images are the mirrored ones. So a table value equals
// that of its mirror point along every axis, and the first-moment table of component a changes
// sign along axis a. Computing one point of each mirror orbit and copying the others cuts the
// work of a table by up to 8. Classes whose mirror is not their own representative (D = k/2 for
// an even k: the mirror point is an image of the point, but the tables' quadratic term is not
// periodic) are computed as they are.
struct TableMirror {
  std::vector<int> to[3];    // per axis and coordinate: the mirror coordinate, or -1 (none)
  // rep[d][c]: the class offset D of coordinate c; m points per class; slab_z: axis 2 has the
  // classes D = -(k_z - 1) .. k_z - 1 (no images)
  TableMirror(const std::vector<int> rep[3], const int k[3], int m, bool slab_z)
  {
    for (int d = 0; d < 3; ++d) {
      const int nc = (int) rep[d].size();
      to[d].assign(nc, -1);
      for (int c = 0; c < nc; ++c) {
        const int a = c / m, i = c % m, D = rep[d][c];
        int a2;
        if (d == 2 && slab_z) a2 = (k[2] - 1) - D;    // the class of offset -D
        else a2 = (k[d] - a) % k[d];
        const int c2 = a2 * m + (m - 1 - i);
        if (c2 >= 0 && c2 < nc && rep[d][c2] == -D) to[d][c] = c2;
      }
    }
  }
  // the point computed for coordinate c along axis d (its mirror when that comes first)
  int source(int d, int c) const { return to[d][c] >= 0 && to[d][c] < c ? to[d][c] : c; }
  bool computed(int x, int y, int z) const { return source(0, x) == x && source(1, y) == y && source(2, z) == z; }
  // v[(x nc1 + y) nc2 + z] (and moment[a nv + ...] when not null, odd along axis a) of the points
  // not computed, from those that are
  void fill(std::vector<double> &v, std::vector<double> *moment) const
  {
    const int nc[3] = {(int) to[0].size(), (int) to[1].size(), (int) to[2].size()};
    const std::size_t nv = v.size();
#pragma omp parallel for schedule(static)
    for (int x = 0; x < nc[0]; ++x)
      for (int y = 0; y < nc[1]; ++y)
        for (int z = 0; z < nc[2]; ++z) {
          const int c[3] = {x, y, z}, sc[3] = {source(0, x), source(1, y), source(2, z)};
          if (sc[0] == x && sc[1] == y && sc[2] == z) continue;
          const std::size_t at = ((std::size_t) x * nc[1] + y) * nc[2] + z;
          const std::size_t from = ((std::size_t) sc[0] * nc[1] + sc[1]) * nc[2] + sc[2];
          v[at] = v[from];
          if (moment)
            for (int a = 0; a < 3; ++a) (*moment)[a * nv + at] = (sc[a] != c[a] ? -1.0 : 1.0) * (*moment)[a * nv + from];
        }
  }
};

// Values of K_D (periodic_grid.h) in unit-grid coordinates (cell half-widths cs_d, largest 1;
// surfaces of half-widths ss_d and near depths m_d: grid_near_depth)
// at every r_d = 2 D_d cs_d + i dx ss_d, D the class representative in (-k_d/2, k_d/2], i in
// [-(p-1), p-1]: a tensor grid of k_d (2p - 1) coordinates along axis d. With K the largest
// periodic half-width k_d cs_d, G_per(r) = G_per,unit(r / K) / K, by the Ewald split of the
// unit cell of half-widths k_d cs_d / K: real-space terms (the excluded near images in regular
// form, -erf / rho), the reciprocal sum (separable on the tensor grid: three contractions) and
// the background. v[(x * nc1 + y) * nc2 + z].
std::vector<double> grid_kernel_values(const KernelSpec &unit, const int k[3], int p, const double cs[3],
                                       std::vector<double> *moment = nullptr)
{
  double K = 0, box[3];
  for (int d = 0; d < 3; ++d) K = std::max(K, k[d] * cs[d]);
  for (int d = 0; d < 3; ++d) box[d] = k[d] * cs[d] == K ? 1.0 : k[d] * cs[d] / K;
  const Split s(unit, box);
  const int m = 2 * p - 1;
  const int nc[3] = {k[0] * m, k[1] * m, k[2] * m};
  const double dx = p > 1 ? 2.0 * kRadiusInner / (p - 1) : 0.0;
  int near[3];
  double ss[3];
  grid_near_depth(cs, near, ss);
  std::vector<int> rep[3];     // class representative of each 1D coordinate
  std::vector<double> u[3];    // unit-cell coordinate (r / K)
  std::vector<double> zeta[3];    // its part within the cells: (check - centre) - (equivalent - centre)
  for (int d = 0; d < 3; ++d) {
    rep[d].resize(nc[d]);
    u[d].resize(nc[d]);
    zeta[d].resize(nc[d]);
    for (int a = 0; a < k[d]; ++a)
      for (int i = 0; i < m; ++i) {
        const int D = grid_class_representative(a, k[d]);
        rep[d][a * m + i] = D;
        u[d][a * m + i] = (2.0 * D * cs[d] + (i - (p - 1)) * dx * ss[d]) / K;
        zeta[d][a * m + i] = (i - (p - 1)) * dx * ss[d] / K;
      }
  }
  // reciprocal sum Re sum_m W(k) e^{i k.u}, k_d = pi m_d / box_d
  int Km[3], M[3];
  std::vector<std::complex<double>> E[3];
  for (int d = 0; d < 3; ++d) {
    Km[d] = s.direct ? 0 : s.kmax_axis(d);
    M[d] = 2 * Km[d] + 1;
    E[d].resize((std::size_t) nc[d] * M[d]);
    for (int c = 0; c < nc[d]; ++c)
      for (int q = 0; q < M[d]; ++q)
        E[d][(std::size_t) c * M[d] + q] = std::polar(1.0, kPi * (q - Km[d]) * u[d][c] / box[d]);
  }
  // reciprocal weights: W(k) for G_per; first moments (moment tables) c_a(k) =
  // (4 pi / V) k_a exp(-k^2 / 4 alpha^2) (2 / k^4 + 1 / (2 alpha^2 k^2)), the coefficients of
  // sin(k.u) in P_a(u) = sum_n (u + n L)_a G(u + n L)
  const int nsets = moment ? 4 : 1;
  std::vector<std::vector<double>> W(nsets, std::vector<double>((std::size_t) M[0] * M[1] * M[2], 0.0));
  for (int a = 0; a < M[0]; ++a)
    for (int b = 0; b < M[1]; ++b)
      for (int c = 0; c < M[2]; ++c) {
        const int mv[3] = {a - Km[0], b - Km[1], c - Km[2]};
        if (!s.k_inside(mv)) continue;
        const std::size_t at = ((std::size_t) a * M[1] + b) * M[2] + c;
        const double k2 = s.k2_of(mv);
        W[0][at] = s.weight_k2(k2);
        if (!moment || k2 == 0.0) continue;
        const double al2 = s.alpha * s.alpha, q2 = k2 + s.kappa * s.kappa;    // Yukawa: k^2 + kappa^2
        const double f = (4 * kPi / s.volume) * std::exp(-q2 / (4 * al2)) * (2 / (q2 * q2) + 1 / (2 * al2 * q2));
        for (int d = 0; d < 3; ++d) W[1 + d][at] = f * kPi * mv[d] / s.shape[d];
      }
  // sum_m W(m) e^{i k.u} contracted over the z and y axes (separable): B[set][(a * nc1 + y) * nc2 + z]
  std::vector<std::vector<std::complex<double>>> B(nsets);
  for (int set = 0; set < nsets; ++set) {
    std::vector<std::complex<double>> A((std::size_t) M[0] * M[1] * nc[2]);
    B[set].resize((std::size_t) M[0] * nc[1] * nc[2]);
    const std::vector<double> &Ws = W[set];
#pragma omp parallel for schedule(static)
    for (int ab = 0; ab < M[0] * M[1]; ++ab)
      for (int z = 0; z < nc[2]; ++z) {
        std::complex<double> acc = 0;
        for (int c = 0; c < M[2]; ++c) acc += Ws[(std::size_t) ab * M[2] + c] * E[2][(std::size_t) z * M[2] + c];
        A[(std::size_t) ab * nc[2] + z] = acc;
      }
#pragma omp parallel for schedule(static)
    for (int a = 0; a < M[0]; ++a)
      for (int y = 0; y < nc[1]; ++y)
        for (int z = 0; z < nc[2]; ++z) {
          std::complex<double> acc = 0;
          for (int b = 0; b < M[1]; ++b)
            acc += E[1][(std::size_t) y * M[1] + b] * A[((std::size_t) a * M[1] + b) * nc[2] + z];
          B[set][((std::size_t) a * nc[1] + y) * nc[2] + z] = acc;
        }
  }
  const std::size_t nv = (std::size_t) nc[0] * nc[1] * nc[2];
  std::vector<double> v(nv);
  if (moment) moment->assign(3 * nv, 0.0);
  const double quad_unit = s.yukawa ? 0.0 : 2 * kPi / (3 * s.volume);
  const double cut = s.real_cut();
  const TableMirror mirror(rep, k, m, false);
#pragma omp parallel for schedule(dynamic, 1)
  for (int x = 0; x < nc[0]; ++x)
    for (int y = 0; y < nc[1]; ++y)
      for (int z = 0; z < nc[2]; ++z) {
        if (!mirror.computed(x, y, z)) continue;
        std::complex<double> acc[4] = {0, 0, 0, 0};
        for (int set = 0; set < nsets; ++set)
          for (int a = 0; a < M[0]; ++a)
            acc[set] += E[0][(std::size_t) x * M[0] + a] * B[set][((std::size_t) a * nc[1] + y) * nc[2] + z];
        double val = acc[0].real() + s.background();
        double pm[3] = {acc[1].imag(), acc[2].imag(), acc[3].imag()};    // P_a
        const double r[3] = {u[0][x], u[1][y], u[2][z]};
        const int D[3] = {rep[0][x], rep[1][y], rep[2][z]};
        // images within the real-space cutoff per axis, and the excluded ones (the near field,
        // |D + k n| <= m: with m = 1, n = 0 when k >= 3; with 2 cells along an axis the class
        // D = 1 has two (n = 0, -1), with 1 cell three (n = -1, 0, 1))
        std::vector<int> cand[3];
        for (int c = 0; c < 3; ++c) {
          const int Q = std::max(s.images(c, std::fabs(r[c])), near[c] / k[c] + 1);
          for (int q = -Q; q <= Q; ++q)
            if (std::abs(r[c] + s.period[c] * q) <= cut || std::abs(D[c] + k[c] * q) <= near[c]) cand[c].push_back(q);
        }
        for (int n0 : cand[0])
          for (int n1 : cand[1])
            for (int n2 : cand[2]) {
              const int n[3] = {n0, n1, n2};
              bool excluded = true;    // the image is adjacent to the target cell
              double d2 = 0;
              for (int c = 0; c < 3; ++c) {
                excluded = excluded && std::abs(D[c] + k[c] * n[c]) <= near[c];
                const double d = r[c] + s.period[c] * n[c];
                d2 += d * d;
              }
              const double rho = std::sqrt(d2);
              if (s.direct) {    // direct image sum (Yukawa, kappa >= 10): the excluded terms are left out
                if (excluded || rho > cut) continue;
                double t, F;
                s.real(rho, false, t, F);
                val += t;
                if (moment)
                  for (int d = 0; d < 3; ++d) pm[d] += (r[d] + s.period[d] * n[d]) * t;
                continue;
              }
              if (excluded && rho == 0.0) {
                val += s.reg0();
                continue;
              }
              if (!excluded && rho > cut) continue;
              double t, F;
              s.real(rho, excluded, t, F);
              val += t;
              if (moment)
                for (int d = 0; d < 3; ++d) pm[d] += (r[d] + s.period[d] * n[d]) * t;
            }
        const std::size_t at = ((std::size_t) x * nc[1] + y) * nc[2] + z;
        if (moment) {
          // offset-weighted kernel sum_n (D_n)_a G(r_n) = P_a(r) - zeta_a G_per(r) (D_n = r_n - zeta:
          // the offset of the cells' centres), less its non-harmonic part N_a(zeta) =
          // -(2 pi / 5 V) zeta_a |zeta|^2 (lap N_a = -(4 pi / V) zeta_a, from the background),
          // added exactly at the targets; scale-free (degree 0)
          const double zt[3] = {zeta[0][x], zeta[1][y], zeta[2][z]};
          const double z2 = zt[0] * zt[0] + zt[1] * zt[1] + zt[2] * zt[2];
          const double cN = s.yukawa ? 0.0 : 2 * kPi / (5 * s.volume);    // Yukawa: no background
          for (int d = 0; d < 3; ++d) (*moment)[d * nv + at] = pm[d] - zt[d] * val + cN * zt[d] * z2;
        }
        val -= quad_unit * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        v[at] = val / K;
      }
  mirror.fill(v, moment);
  return v;
}

// Slab (periodic in x and y, open in z): K_D at x, y as above (classes mod k_d), at z on
// 2 D_z cs_z + i dx ss_z for D_z in [-(k_z - 1), k_z - 1] (no images in z), G_2 the doubly
// periodic sum of slab_ewald.h for the unit cell of half-widths k_d cs_d / K in x and y (K the
// larger), excluding the images in the target cell's near field (|D_x + k_x n_x| <= m_x,
// |D_y + k_y n_y| <= m_y, |D_z| <= m_z).
// No quadratic part (G_2 is harmonic). v[(x * nc1 + y) * nc2 + z], nc2 = (2 k_z - 1)(2p - 1).
// With moment: the offset-weighted kernels of the virial as in grid_kernel_values, from
// P_a(r) = sum_n (r + n L)_a G(r + n L) over the x-y lattice: real space (r_n)_a erfc(alpha r_n) /
// r_n; reciprocal, for a in x, y, the transform of rho_a f(rho, z) (f the smooth part), i d/dk_a
// of the weight: -sum_k (k_a / k) dw/dk(k, z) sin(k.rho) (its k = 0 term vanishes by the
// lattice's reflection symmetry); for a = z, P_z = r_z G_2 (no images in z). The kernels are
// harmonic (no background part).
std::vector<double> slab_kernel_values(const int k[3], int p, const double cs[3], std::vector<double> *moment = nullptr)
{
  const double K = std::max(k[0] * cs[0], k[1] * cs[1]);
  double box[2];
  for (int d = 0; d < 2; ++d) box[d] = k[d] * cs[d] == K ? 1.0 : k[d] * cs[d] / K;
  const SlabSplit s(box);
  const int m = 2 * p - 1;
  const int nc[3] = {k[0] * m, k[1] * m, (2 * k[2] - 1) * m};
  const double dx = p > 1 ? 2.0 * kRadiusInner / (p - 1) : 0.0;
  int near[3];
  double ss[3];
  grid_near_depth(cs, near, ss);
  std::vector<int> rep[3];
  std::vector<double> u[3], zeta[3];
  for (int d = 0; d < 3; ++d) {
    rep[d].resize(nc[d]);
    u[d].resize(nc[d]);
    zeta[d].resize(nc[d]);
    const int nclass = d < 2 ? k[d] : 2 * k[2] - 1;
    for (int a = 0; a < nclass; ++a)
      for (int i = 0; i < m; ++i) {
        const int D = d < 2 ? grid_class_representative(a, k[d]) : a - (k[2] - 1);
        rep[d][a * m + i] = D;
        u[d][a * m + i] = (2.0 * D * cs[d] + (i - (p - 1)) * dx * ss[d]) / K;
        zeta[d][a * m + i] = (i - (p - 1)) * dx * ss[d] / K;
      }
  }
  // reciprocal sum over the whole plane of m: Re sum w(|k|, z) e^{i k.rho}
  int Km[2], M[2];
  std::vector<std::complex<double>> E[2];
  for (int d = 0; d < 2; ++d) {
    Km[d] = s.kmax_axis(d);
    M[d] = 2 * Km[d] + 1;
    E[d].resize((std::size_t) nc[d] * M[d]);
    for (int c = 0; c < nc[d]; ++c)
      for (int q = 0; q < M[d]; ++q)
        E[d][(std::size_t) c * M[d] + q] = std::polar(1.0, kPi * (q - Km[d]) * u[d][c] / box[d]);
  }
  // A[set][a][y][z] = sum_b w_set(k_ab, z) E1[y][b]; sets: w, and with moment (k_x/k) dw/dk,
  // (k_y/k) dw/dk
  const int nsets = moment ? 3 : 1;
  std::vector<std::vector<std::complex<double>>> A(nsets, std::vector<std::complex<double>>((std::size_t) M[0] * nc[1] * nc[2]));
#pragma omp parallel for schedule(dynamic, 1)
  for (int a = 0; a < M[0]; ++a) {
    std::vector<double> w((std::size_t) nsets * M[1] * nc[2], 0.0);
    for (int b = 0; b < M[1]; ++b) {
      const double kk = s.k_of(a - Km[0], b - Km[1]);
      if (kk <= 0) continue;
      const double kv[2] = {kPi * (a - Km[0]) / box[0], kPi * (b - Km[1]) / box[1]};
      for (int z = 0; z < nc[2]; ++z) {
        double wv, dw;
        s.weight(kk, u[2][z], wv, dw);
        w[(std::size_t) b * nc[2] + z] = wv;
        if (!moment) continue;
        const double dk = s.weight_dk(kk, u[2][z]);
        for (int d = 0; d < 2; ++d) w[((std::size_t) (1 + d) * M[1] + b) * nc[2] + z] = kv[d] / kk * dk;
      }
    }
    for (int set = 0; set < nsets; ++set)
      for (int y = 0; y < nc[1]; ++y)
        for (int z = 0; z < nc[2]; ++z) {
          std::complex<double> acc = 0;
          for (int b = 0; b < M[1]; ++b)
            acc += w[((std::size_t) set * M[1] + b) * nc[2] + z] * E[1][(std::size_t) y * M[1] + b];
          A[set][((std::size_t) a * nc[1] + y) * nc[2] + z] = acc;
        }
  }
  const std::size_t nv = (std::size_t) nc[0] * nc[1] * nc[2];
  std::vector<double> v(nv);
  if (moment) moment->assign(3 * nv, 0.0);
  const double cut = s.real_cut();
  const TableMirror mirror(rep, k, m, true);
#pragma omp parallel for schedule(dynamic, 1)
  for (int x = 0; x < nc[0]; ++x)
    for (int y = 0; y < nc[1]; ++y)
      for (int z = 0; z < nc[2]; ++z) {
        if (!mirror.computed(x, y, z)) continue;
        std::complex<double> acc[3] = {0, 0, 0};
        for (int set = 0; set < nsets; ++set)
          for (int a = 0; a < M[0]; ++a)
            acc[set] += E[0][(std::size_t) x * M[0] + a] * A[set][((std::size_t) a * nc[1] + y) * nc[2] + z];
        const double r[3] = {u[0][x], u[1][y], u[2][z]};
        const int D[3] = {rep[0][x], rep[1][y], rep[2][z]};
        double z0, dz0;
        s.zero_term(r[2], z0, dz0);
        double val = acc[0].real() + z0;
        double pm[2] = {-acc[1].imag(), -acc[2].imag()};    // P_x, P_y
        std::vector<int> cand[2];
        for (int c = 0; c < 2; ++c) {
          const int Q = std::max(s.images(c, std::fabs(r[c])), near[c] / k[c] + 1);
          for (int q = -Q; q <= Q; ++q)
            if (std::abs(r[c] + s.period[c] * q) <= cut || std::abs(D[c] + k[c] * q) <= near[c]) cand[c].push_back(q);
        }
        for (int n0 : cand[0])
          for (int n1 : cand[1]) {
            const bool excluded = std::abs(D[0] + k[0] * n0) <= near[0] && std::abs(D[1] + k[1] * n1) <= near[1] &&
                std::abs(D[2]) <= near[2];
            const double d0 = r[0] + s.period[0] * n0, d1 = r[1] + s.period[1] * n1;
            const double rho = std::sqrt(d0 * d0 + d1 * d1 + r[2] * r[2]);
            if (excluded && rho == 0.0) {
              val += s.reg0();
              continue;
            }
            if (!excluded && rho > cut) continue;
            double t, F;
            s.real(rho, excluded, t, F);
            val += t;
            pm[0] += d0 * t;
            pm[1] += d1 * t;
          }
        const std::size_t at = ((std::size_t) x * nc[1] + y) * nc[2] + z;
        if (moment) {
          const double zt[3] = {zeta[0][x], zeta[1][y], zeta[2][z]};
          (*moment)[at] = pm[0] - zt[0] * val;
          (*moment)[nv + at] = pm[1] - zt[1] * val;
          (*moment)[2 * nv + at] = (r[2] - zt[2]) * val;
        }
        v[at] = val / K;
      }
  mirror.fill(v, moment);
  return v;
}

// The grid kernel of the values v (grid_kernel_values, slab_kernel_values layout): per class the
// r2c spectrum of its M2L lattice, then the DFT over the cells.
std::shared_ptr<GridKernel> grid_kernel_from_values(const int k[3], int p, const double cs[3], bool slab, double quad,
                                                    const std::vector<double> &v)
{
  auto g = std::make_shared<GridKernel>();
  g->k = k[0];
  g->slab = slab;
  g->nz = slab ? 2 * k[2] : k[2];
  double V = 1.0;
  for (int d = 0; d < 3; ++d) {
    g->cells[d] = k[d];
    g->cell_shape[d] = cs[d];
    V *= 2.0 * k[d] * cs[d];
  }
  g->p = p;
  g->nraw = m2l_nfreq_raw(p);
  g->nfreq = grid_row_stride(p);
  g->quad = quad;
  (void) V;
  const int n = m2l_grid_n(p), m = 2 * p - 1;
  const int nzc = slab ? 2 * k[2] - 1 : k[2];    // classes along z
  const int nc1 = k[1] * m, nc2 = nzc * m;
  const std::size_t kc = (std::size_t) k[0] * k[1] * nzc, ns = g->slots();
  std::complex<double> *z = grid_alloc((std::size_t) g->nfreq * ns);
  std::fill(z, z + (std::size_t) g->nfreq * ns, std::complex<double>(0.0));
  {
    std::lock_guard<std::mutex> lock(fftw_mutex());
    const int dims[3] = {k[0], k[1], g->nz};
    auto *zz = reinterpret_cast<fftw_complex *>(z);
    const int nf = g->nfreq;    // 16 contiguous frequencies of every cell, cells nf apart
    g->plan_fwd = fftw_plan_many_dft(3, dims, 16, zz, nullptr, nf, 1, zz, nullptr, nf, 1, FFTW_FORWARD, FFTW_ESTIMATE);
    g->plan_bwd = fftw_plan_many_dft(3, dims, 16, zz, nullptr, nf, 1, zz, nullptr, nf, 1, FFTW_BACKWARD, FFTW_ESTIMATE);
    if (!g->plan_fwd || !g->plan_bwd) throw std::runtime_error("kifmm: FFTW plan creation failed");
  }
  const double norm = 1.0 / ((double) n * n * n * (double) ns);
#pragma omp parallel
  {
    double *grid;
    fftw_complex *spec;
    fftw_plan plan;
    {
      std::lock_guard<std::mutex> lock(fftw_mutex());
      grid = fftw_alloc_real((std::size_t) n * n * n);
      spec = fftw_alloc_complex(g->nraw);
      plan = fftw_plan_dft_r2c_3d(n, n, n, grid, spec, FFTW_ESTIMATE);
    }
#pragma omp for schedule(dynamic, 1)
    for (int cls = 0; cls < (int) kc; ++cls) {
      const int a[3] = {cls / (k[1] * nzc), (cls / nzc) % k[1], cls % nzc};
      // slot of the class: along z the offset D_z = a[2] - (k_z - 1) modulo the padded length
      const std::size_t at = ((std::size_t) a[0] * k[1] + a[1]) * g->nz +
          (slab ? (a[2] - (k[2] - 1) + g->nz) % g->nz : a[2]);
      std::fill(grid, grid + (std::size_t) n * n * n, 0.0);
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
          for (int l = 0; l < m; ++l) {
            const int gi = (i - (p - 1) + n) % n, gj = (j - (p - 1) + n) % n, gl = (l - (p - 1) + n) % n;
            grid[((std::size_t) gi * n + gj) * n + gl] =
                v[((std::size_t) (a[0] * m + i) * nc1 + a[1] * m + j) * nc2 + a[2] * m + l];
          }
      fftw_execute_dft_r2c(plan, grid, spec);
      for (int f = 0; f < g->nraw; ++f) z[at * g->nfreq + f] = std::complex<double>(spec[f][0], spec[f][1]) * norm;
    }
    std::lock_guard<std::mutex> lock(fftw_mutex());
    fftw_destroy_plan(plan);
    fftw_free(grid);
    fftw_free(spec);
  }
  for (int f = 0; f < g->nfreq; f += 16) {
    auto *col = reinterpret_cast<fftw_complex *>(z + f);
    fftw_execute_dft((fftw_plan) g->plan_fwd, col, col);
  }
  g->hat.assign(z, z + (std::size_t) g->nfreq * ns);
  grid_free(z);
  return g;
}

std::shared_ptr<GridKernel> compute_grid_kernel(const KernelSpec &unit, const int k[3], int p, const double cs[3],
                                                bool slab)
{
  if (std::min(k[0], std::min(k[1], k[2])) < 1) throw std::invalid_argument("kifmm: a periodic grid needs cells");
  if (slab && unit.type != KernelType::Laplace)
    throw std::invalid_argument("kifmm: the slab (periodic_dims 2) is for the Laplace kernel");
  double V = 1.0;
  for (int d = 0; d < 3; ++d) V *= 2.0 * k[d] * cs[d];
  const double quad = unit.type == KernelType::Yukawa || slab ? 0.0 : 2 * kPi / (3.0 * V);
  return grid_kernel_from_values(k, p, cs, slab, quad, slab ? slab_kernel_values(k, p, cs) : grid_kernel_values(unit, k, p, cs));
}

}    // namespace

std::shared_ptr<const GridKernel> periodic_grid_kernel(const KernelSpec &unit, const int cells[3], int p,
                                                       const double *cell_shape, bool slab)
{
  (void) fftw_mutex();    // constructed before the cache below, so destroyed after it (~GridKernel locks it)
  static std::mutex mtx;
  using Key = std::tuple<double, int, int, int, int, double, double, double, bool>;
  static std::map<Key, std::shared_ptr<const GridKernel>> cache;
  const double one[3] = {1.0, 1.0, 1.0};
  const double *cs = cell_shape ? cell_shape : one;
  const Key key{unit.type == KernelType::Yukawa ? unit.kappa : -1.0, cells[0], cells[1], cells[2], p,
                cs[0], cs[1], cs[2], slab};
  std::lock_guard<std::mutex> lock(mtx);    // one computation per key, others wait for it
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  if (cache.size() > 16) cache.clear();    // boxes that keep changing size (yukawa) or shape
  auto g = compute_grid_kernel(unit, cells, p, cs, slab);
  cache[key] = g;
  return g;
}

std::shared_ptr<const GridMomentKernels> periodic_grid_moment_kernels(const KernelSpec &unit, const int cells[3], int p,
                                                                      const double *cell_shape, bool slab)
{
  (void) fftw_mutex();
  static std::mutex mtx;
  using Key = std::tuple<double, int, int, int, int, double, double, double, bool>;
  static std::map<Key, std::shared_ptr<const GridMomentKernels>> cache;
  const double one[3] = {1.0, 1.0, 1.0};
  const double *cs = cell_shape ? cell_shape : one;
  if (slab && unit.type != KernelType::Laplace)
    throw std::invalid_argument("kifmm: the slab (periodic_dims 2) is for the Laplace kernel");
  const Key key{unit.type == KernelType::Yukawa ? unit.kappa : -1.0, cells[0], cells[1], cells[2], p,
                cs[0], cs[1], cs[2], slab};
  std::lock_guard<std::mutex> lock(mtx);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  if (cache.size() > 8) cache.clear();
  if (std::min(cells[0], std::min(cells[1], cells[2])) < 1)
    throw std::invalid_argument("kifmm: a periodic grid needs cells");
  std::vector<double> mom;
  if (slab) slab_kernel_values(cells, p, cs, &mom);
  else grid_kernel_values(unit, cells, p, cs, &mom);
  auto g = std::make_shared<GridMomentKernels>();
  const std::size_t nv = mom.size() / 3;
  for (int a = 0; a < 3; ++a)
    g->a[a] = grid_kernel_from_values(cells, p, cs, slab, 0.0,
                                      std::vector<double>(mom.begin() + a * nv, mom.begin() + (a + 1) * nv));
  cache[key] = g;
  return g;
}

}    // namespace kifmm
