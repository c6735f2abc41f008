// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "periodic_grid.h"

#include "ewald_split.h"
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
  const std::size_t kc = (std::size_t) g.k * g.k * g.k, nf = g.nfreq;
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

// Values of K_D (periodic_grid.h) in unit-grid coordinates at every r = 2 D + i dx, D the
// class representative in (-k/2, k/2]^3, i in [-(p-1), p-1]^3: a tensor grid of k (2p - 1)
// coordinates per axis. G_per(r) = G_per,unit(r / k) / k (period 2k), by the Ewald split of
// the unit cell: real-space terms (the excluded near images in regular form, -erf / rho),
// the reciprocal sum (separable on the tensor grid: three contractions) and the background.
std::vector<double> grid_kernel_values(const KernelSpec &unit, int k, int p)
{
  const Split s(unit);
  const int m = 2 * p - 1, nc = k * m;
  const double dx = p > 1 ? 2.0 * kRadiusInner / (p - 1) : 0.0;
  std::vector<int> rep(nc);    // class representative of each 1D coordinate
  std::vector<double> u(nc);   // unit-cell coordinate (r / k)
  for (int a = 0; a < k; ++a)
    for (int i = 0; i < m; ++i) {
      const int D = grid_class_representative(a, k);
      rep[a * m + i] = D;
      u[a * m + i] = (2.0 * D + (i - (p - 1)) * dx) / k;
    }
  // reciprocal sum Re sum_m W(|m|^2) e^{i pi m.u}
  const int K = s.kmax, M = 2 * K + 1;
  std::vector<std::complex<double>> E((std::size_t) nc * M);
  for (int c = 0; c < nc; ++c)
    for (int q = 0; q < M; ++q) E[(std::size_t) c * M + q] = std::polar(1.0, kPi * (q - K) * u[c]);
  std::vector<double> W((std::size_t) M * M * M);
  for (int a = 0; a < M; ++a)
    for (int b = 0; b < M; ++b)
      for (int c = 0; c < M; ++c) {
        const int m2 = (a - K) * (a - K) + (b - K) * (b - K) + (c - K) * (c - K);
        W[((std::size_t) a * M + b) * M + c] = m2 > K * K ? 0.0 : s.weight(m2);
      }
  std::vector<std::complex<double>> A((std::size_t) M * M * nc), B((std::size_t) M * nc * nc);
#pragma omp parallel for schedule(static)
  for (int ab = 0; ab < M * M; ++ab)
    for (int z = 0; z < nc; ++z) {
      std::complex<double> acc = 0;
      for (int c = 0; c < M; ++c) acc += W[(std::size_t) ab * M + c] * E[(std::size_t) z * M + c];
      A[(std::size_t) ab * nc + z] = acc;
    }
#pragma omp parallel for schedule(static)
  for (int a = 0; a < M; ++a)
    for (int y = 0; y < nc; ++y)
      for (int z = 0; z < nc; ++z) {
        std::complex<double> acc = 0;
        for (int b = 0; b < M; ++b) acc += E[(std::size_t) y * M + b] * A[((std::size_t) a * M + b) * nc + z];
        B[((std::size_t) a * nc + y) * nc + z] = acc;
      }
  std::vector<double> v((std::size_t) nc * nc * nc);
  const double quad_unit = s.yukawa ? 0.0 : 2 * kPi / (3 * kVolume);
#pragma omp parallel for schedule(dynamic, 1)
  for (int x = 0; x < nc; ++x)
    for (int y = 0; y < nc; ++y)
      for (int z = 0; z < nc; ++z) {
        std::complex<double> acc = 0;
        for (int a = 0; a < M; ++a) acc += E[(std::size_t) x * M + a] * B[((std::size_t) a * nc + y) * nc + z];
        double val = acc.real() + s.background();
        const double r[3] = {u[x], u[y], u[z]};
        const int D[3] = {rep[x], rep[y], rep[z]};
        // images within the real-space cutoff per axis, and the excluded ones (n = 0 there:
        // |D| <= k/2 and k >= 3 make |D + k n| <= 1 impossible for n != 0)
        int cand[3][5], nc3[3] = {0, 0, 0};
        for (int c = 0; c < 3; ++c)
          for (int q = -2; q <= 2; ++q)
            if (s.direct || std::abs(r[c] + kPeriod * q) <= kRealCut || std::abs(D[c] + k * q) <= 1)
              cand[c][nc3[c]++] = q;
        for (int ix = 0; ix < nc3[0]; ++ix)
          for (int iy = 0; iy < nc3[1]; ++iy)
            for (int iz = 0; iz < nc3[2]; ++iz) {
              const int n[3] = {cand[0][ix], cand[1][iy], cand[2][iz]};
              bool excluded = true;    // the image is adjacent to the target cell
              double d2 = 0;
              for (int c = 0; c < 3; ++c) {
                excluded = excluded && std::abs(D[c] + k * n[c]) <= 1;
                const double d = r[c] + kPeriod * n[c];
                d2 += d * d;
              }
              const double rho = std::sqrt(d2);
              if (s.direct) {    // direct image sum (Yukawa, kappa >= 10): the excluded terms are left out
                if (excluded) continue;
                double t, F;
                s.real(rho, false, t, F);
                val += t;
                continue;
              }
              if (excluded && rho == 0.0) {
                val += s.reg0();
                continue;
              }
              if (!excluded && rho > kRealCut) continue;
              double t, F;
              s.real(rho, excluded, t, F);
              val += t;
            }
        val -= quad_unit * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        v[((std::size_t) x * nc + y) * nc + z] = val / k;
      }
  return v;
}

std::shared_ptr<GridKernel> compute_grid_kernel(const KernelSpec &unit, int k, int p)
{
  if (k < 3) throw std::invalid_argument("kifmm: a periodic grid needs at least 3 cells per side");
  auto g = std::make_shared<GridKernel>();
  g->k = k;
  g->p = p;
  g->nraw = m2l_nfreq_raw(p);
  g->nfreq = m2l_nfreq(p);
  g->quad = unit.type == KernelType::Yukawa ? 0.0 : 2 * kPi / (3.0 * (2.0 * k) * (2.0 * k) * (2.0 * k));
  const int n = m2l_grid_n(p), m = 2 * p - 1, nc = k * m;
  const std::size_t kc = (std::size_t) k * k * k;
  const std::vector<double> v = grid_kernel_values(unit, k, p);
  std::complex<double> *z = grid_alloc((std::size_t) g->nfreq * kc);
  std::fill(z, z + (std::size_t) g->nfreq * kc, std::complex<double>(0.0));
  {
    std::lock_guard<std::mutex> lock(fftw_mutex());
    const int dims[3] = {k, k, k};
    auto *zz = reinterpret_cast<fftw_complex *>(z);
    const int nf = g->nfreq;    // 16 contiguous frequencies of every cell, cells nf apart
    g->plan_fwd = fftw_plan_many_dft(3, dims, 16, zz, nullptr, nf, 1, zz, nullptr, nf, 1, FFTW_FORWARD, FFTW_ESTIMATE);
    g->plan_bwd = fftw_plan_many_dft(3, dims, 16, zz, nullptr, nf, 1, zz, nullptr, nf, 1, FFTW_BACKWARD, FFTW_ESTIMATE);
    if (!g->plan_fwd || !g->plan_bwd) throw std::runtime_error("kifmm: FFTW plan creation failed");
  }
  const double norm = 1.0 / ((double) n * n * n * (double) kc);
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
      const int a[3] = {cls / (k * k), (cls / k) % k, cls % k};
      std::fill(grid, grid + (std::size_t) n * n * n, 0.0);
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
          for (int l = 0; l < m; ++l) {
            const int gi = (i - (p - 1) + n) % n, gj = (j - (p - 1) + n) % n, gl = (l - (p - 1) + n) % n;
            grid[((std::size_t) gi * n + gj) * n + gl] =
                v[((std::size_t) (a[0] * m + i) * nc + a[1] * m + j) * nc + a[2] * m + l];
          }
      fftw_execute_dft_r2c(plan, grid, spec);
      for (int f = 0; f < g->nraw; ++f) z[(std::size_t) cls * g->nfreq + f] = std::complex<double>(spec[f][0], spec[f][1]) * norm;
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
  g->hat.assign(z, z + (std::size_t) g->nfreq * kc);
  grid_free(z);
  return g;
}

}    // namespace

std::shared_ptr<const GridKernel> periodic_grid_kernel(const KernelSpec &unit, int k, int p)
{
  (void) fftw_mutex();    // constructed before the cache below, so destroyed after it (~GridKernel locks it)
  static std::mutex mtx;
  static std::map<std::tuple<double, int, int>, std::shared_ptr<const GridKernel>> cache;
  const double key = unit.type == KernelType::Yukawa ? unit.kappa : -1.0;
  std::lock_guard<std::mutex> lock(mtx);    // one computation per (kernel, k, p), others wait for it
  auto it = cache.find({key, k, p});
  if (it != cache.end()) return it->second;
  if (cache.size() > 16) cache.clear();    // yukawa boxes that keep changing size
  auto g = compute_grid_kernel(unit, k, p);
  cache[{key, k, p}] = g;
  return g;
}

}    // namespace kifmm
