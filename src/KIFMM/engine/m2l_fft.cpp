// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "m2l_fft.h"

#include "surface.h"

#include <fftw3.h>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

namespace kifmm {

std::mutex &fftw_mutex()
{
  static std::mutex m;
  return m;
}

namespace {

struct OffsetTable {
  int idx[343];
  OffsetTable()
  {
    int c = 0;
    for (int dx = -3; dx <= 3; ++dx)
      for (int dy = -3; dy <= 3; ++dy)
        for (int dz = -3; dz <= 3; ++dz) {
          const bool adj = std::abs(dx) <= 1 && std::abs(dy) <= 1 && std::abs(dz) <= 1;
          idx[(dx + 3) * 49 + (dy + 3) * 7 + (dz + 3)] = adj ? -1 : c++;
        }
  }
};
const OffsetTable &offsets()
{
  static OffsetTable t;
  return t;
}
}    // namespace

int m2l_offset_index(int dx, int dy, int dz)
{
  if (dx < -3 || dx > 3 || dy < -3 || dy > 3 || dz < -3 || dz > 3) return -1;
  return offsets().idx[(dx + 3) * 49 + (dy + 3) * 7 + (dz + 3)];
}

void m2l_kernel_transforms(const UnitKernel &k, int p, std::vector<double> &hat, int &nfreq)
{
  const int n = m2l_grid_n(p);
  nfreq = m2l_nfreq(p);
  const int nraw = m2l_nfreq_raw(p);
  hat.assign((std::size_t) kM2LKernels * 2 * nfreq, 0.0);
  const double dx = p > 1 ? 2.0 * kRadiusInner / (p - 1) : 0.0;
  const double norm = 1.0 / (double(n) * n * n);
  double *grid;
  fftw_complex *spec;
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(fftw_mutex());
    grid = fftw_alloc_real((std::size_t) n * n * n);
    spec = fftw_alloc_complex(nraw);
    plan = fftw_plan_dft_r2c_3d(n, n, n, grid, spec, FFTW_ESTIMATE);
  }
  for (int ox = -3; ox <= 3; ++ox)
    for (int oy = -3; oy <= 3; ++oy)
      for (int oz = -3; oz <= 3; ++oz) {
        const int id = m2l_offset_index(ox, oy, oz);
        if (id < 0) continue;
        std::fill(grid, grid + (std::size_t) n * n * n, 0.0);
        for (int i = -(p - 1); i <= p - 1; ++i)
          for (int j = -(p - 1); j <= p - 1; ++j)
            for (int l = -(p - 1); l <= p - 1; ++l) {
              const double rx = (2.0 * ox + i * dx) * k.shape[0], ry = (2.0 * oy + j * dx) * k.shape[1],
                           rz = (2.0 * oz + l * dx) * k.shape[2];
              const int gi = (i + n) % n, gj = (j + n) % n, gl = (l + n) % n;
              grid[((std::size_t) gi * n + gj) * n + gl] = k.g(rx * rx + ry * ry + rz * rz);
            }
        fftw_execute_dft_r2c(plan, grid, spec);
        for (int f = 0; f < nraw; ++f) {
          double *chunk = hat.data() + ((std::size_t) (f / 16) * kM2LKernels + id) * 32;
          chunk[f % 16] = spec[f][0] * norm;
          chunk[16 + f % 16] = spec[f][1] * norm;
        }
      }
  std::lock_guard<std::mutex> lock(fftw_mutex());
  fftw_destroy_plan(plan);
  fftw_free(grid);
  fftw_free(spec);
}

M2LTransform::M2LTransform(int p) : p_(p), n_(m2l_grid_n(p)), nfreq_(m2l_nfreq(p)), nraw_(m2l_nfreq_raw(p))
{
  const std::vector<int> lat = surface_lattice(p);
  surf2grid_.resize(lat.size() / 3);
  for (std::size_t m = 0; m < surf2grid_.size(); ++m)
    surf2grid_[m] = (lat[3 * m] * p_ + lat[3 * m + 1]) * n_ + lat[3 * m + 2];
  // one set of plans per order for the whole process
  struct Plans {
    fftw_plan f[3], b[3];
  };
  static std::map<int, Plans> plans;
  std::lock_guard<std::mutex> lock(fftw_mutex());
  auto it = plans.find(p);
  if (it == plans.end()) {
    const int n = n_, nz = n / 2 + 1;
    double *g = fftw_alloc_real((std::size_t) p * p * n);
    fftw_complex *s = fftw_alloc_complex(nraw_);
    // complex layout [kx][ky][kz] (that of a 3-d r2c transform); real lines [x < p][y < p][z]
    const fftw_iodim along_z = {n, 1, 1}, along_y = {n, nz, nz}, along_x = {n, n * nz, n * nz};
    const fftw_iodim lines_z[2] = {{p, p * n, n * nz}, {p, n, nz}};       // x < p, y < p
    const fftw_iodim lines_y[2] = {{p, n * nz, n * nz}, {nz, 1, 1}};     // x < p, all kz
    const fftw_iodim lines_x[2] = {{n, nz, nz}, {nz, 1, 1}};             // all y, all kz
    const fftw_iodim lines_zb[2] = {{p, n * nz, p * n}, {p, nz, n}};     // back to the real lines
    Plans pl;
    pl.f[0] = fftw_plan_guru_dft_r2c(1, &along_z, 2, lines_z, g, s, FFTW_ESTIMATE);
    pl.f[1] = fftw_plan_guru_dft(1, &along_y, 2, lines_y, s, s, FFTW_FORWARD, FFTW_ESTIMATE);
    pl.f[2] = fftw_plan_guru_dft(1, &along_x, 2, lines_x, s, s, FFTW_FORWARD, FFTW_ESTIMATE);
    pl.b[0] = fftw_plan_guru_dft(1, &along_x, 2, lines_x, s, s, FFTW_BACKWARD, FFTW_ESTIMATE);
    pl.b[1] = fftw_plan_guru_dft(1, &along_y, 2, lines_y, s, s, FFTW_BACKWARD, FFTW_ESTIMATE);
    pl.b[2] = fftw_plan_guru_dft_c2r(1, &along_z, 2, lines_zb, s, g, FFTW_ESTIMATE);
    fftw_free(g);
    fftw_free(s);
    for (int k = 0; k < 3; ++k)
      if (!pl.f[k] || !pl.b[k]) throw std::runtime_error("kifmm: FFTW plan creation failed");
    it = plans.emplace(p, pl).first;
  }
  for (int k = 0; k < 3; ++k) {
    fwd_[k] = (void *) it->second.f[k];
    bwd_[k] = (void *) it->second.b[k];
  }
}

M2LTransform::Workspace::Workspace(const M2LTransform &t)
{
  const int n = m2l_grid_n(t.p());
  grid = fftw_alloc_real((std::size_t) t.p() * t.p() * n);
  spec = (double *) fftw_alloc_complex(t.nfreq());
}

M2LTransform::Workspace::~Workspace()
{
  fftw_free(grid);
  fftw_free(spec);
}

void M2LTransform::forward(const double *equiv, double *hat, std::size_t stride, Workspace &w) const
{
  const int n = n_, p = p_, nz = n / 2 + 1;
  std::memset(w.grid, 0, sizeof(double) * p * p * n);
  for (std::size_t m = 0; m < surf2grid_.size(); ++m) w.grid[surf2grid_[m]] = equiv[m];
  // the passes along y and x read lines that the previous passes do not write: zero them
  for (int x = 0; x < p; ++x)
    std::memset(w.spec + 2 * ((std::size_t) x * n + p) * nz, 0, sizeof(double) * 2 * (n - p) * nz);
  std::memset(w.spec + 2 * (std::size_t) p * n * nz, 0, sizeof(double) * 2 * (n - p) * n * nz);
  fftw_complex *spec = (fftw_complex *) w.spec;
  fftw_execute_dft_r2c((fftw_plan) fwd_[0], w.grid, spec);
  fftw_execute_dft((fftw_plan) fwd_[1], spec, spec);
  fftw_execute_dft((fftw_plan) fwd_[2], spec, spec);
  for (int b = 0; b < nfreq_ / 16; ++b) {
    double *chunk = hat + b * stride;
    for (int j = 0; j < 16; ++j) {
      const int f = 16 * b + j;
      chunk[j] = f < nraw_ ? w.spec[2 * f] : 0.0;
      chunk[16 + j] = f < nraw_ ? w.spec[2 * f + 1] : 0.0;
    }
  }
}

void M2LTransform::inverse_add(const double *hat, std::size_t stride, double *check, double scale, Workspace &w) const
{
  for (int f = 0; f < nraw_; ++f) {
    const double *chunk = hat + (f / 16) * stride;
    w.spec[2 * f] = chunk[f % 16];
    w.spec[2 * f + 1] = chunk[16 + f % 16];
  }
  fftw_complex *spec = (fftw_complex *) w.spec;
  fftw_execute_dft((fftw_plan) bwd_[0], spec, spec);
  fftw_execute_dft((fftw_plan) bwd_[1], spec, spec);
  fftw_execute_dft_c2r((fftw_plan) bwd_[2], spec, w.grid);
  for (std::size_t m = 0; m < surf2grid_.size(); ++m) check[m] += scale * w.grid[surf2grid_[m]];
}

namespace {
struct ChildOffsetTable {
  // rel[slot][s][t]: kernel index of target child t vs source child s of the colleague at slot
  int rel[27][8][8];
  ChildOffsetTable()
  {
    for (int slot = 0; slot < 27; ++slot) {
      const int o[3] = {slot / 9 - 1, (slot / 3) % 3 - 1, slot % 3 - 1};
      for (int s = 0; s < 8; ++s)
        for (int t = 0; t < 8; ++t) {
          int d[3];
          for (int a = 0; a < 3; ++a) d[a] = ((t >> a) & 1) - 2 * o[a] - ((s >> a) & 1);
          rel[slot][s][t] = m2l_offset_index(d[0], d[1], d[2]);
        }
    }
  }
};
const ChildOffsetTable &child_offsets()
{
  static ChildOffsetTable t;
  return t;
}

// y += k .* x over 16 frequencies at offset b (split re/im with stride nfreq)
inline void cmac16(const double *k, const double *x, double *y)
{
#if defined(__AVX512F__)
  const double *ki = k + 16, *xi = x + 16;
  double *yi = y + 16;
  const __m512d kr0 = _mm512_loadu_pd(k), kr1 = _mm512_loadu_pd(k + 8);
  const __m512d ki0 = _mm512_loadu_pd(ki), ki1 = _mm512_loadu_pd(ki + 8);
  const __m512d xr0 = _mm512_loadu_pd(x), xr1 = _mm512_loadu_pd(x + 8);
  const __m512d xi0 = _mm512_loadu_pd(xi), xi1 = _mm512_loadu_pd(xi + 8);
  __m512d yr0 = _mm512_loadu_pd(y), yr1 = _mm512_loadu_pd(y + 8);
  __m512d yi0 = _mm512_loadu_pd(yi), yi1 = _mm512_loadu_pd(yi + 8);
  yr0 = _mm512_fnmadd_pd(ki0, xi0, _mm512_fmadd_pd(kr0, xr0, yr0));
  yr1 = _mm512_fnmadd_pd(ki1, xi1, _mm512_fmadd_pd(kr1, xr1, yr1));
  yi0 = _mm512_fmadd_pd(ki0, xr0, _mm512_fmadd_pd(kr0, xi0, yi0));
  yi1 = _mm512_fmadd_pd(ki1, xr1, _mm512_fmadd_pd(kr1, xi1, yi1));
  _mm512_storeu_pd(y, yr0);
  _mm512_storeu_pd(y + 8, yr1);
  _mm512_storeu_pd(yi, yi0);
  _mm512_storeu_pd(yi + 8, yi1);
#else
  const double *ki = k + 16, *xi = x + 16;
  double *yi = y + 16;
#pragma omp simd
  for (int f = 0; f < 16; ++f) {
    const double a = k[f], bb = ki[f], c = x[f], d = xi[f];
    y[f] += a * c - bb * d;
    yi[f] += a * d + bb * c;
  }
#endif
}
}    // namespace

void m2l_parent_pairs(int nfreq, const double *kernels, int block_begin, int block_end,
                      const std::vector<std::pair<int, int>> *pairs, const double *const *xtab,
                      std::size_t xstride, double *const *ytab, std::size_t ystride)
{
  const ChildOffsetTable &tab = child_offsets();
  (void) nfreq;
  for (int blk = block_begin; blk < block_end; ++blk) {
    const double *kb = kernels + (std::size_t) blk * kM2LKernels * 32;
    const std::size_t xo = blk * xstride, yo = blk * ystride;
    for (int slot = 0; slot < 27; ++slot) {
      const auto &pl = pairs[slot];
      if (pl.empty()) continue;
      const double *kp[8][8];
      for (int s = 0; s < 8; ++s)
        for (int t = 0; t < 8; ++t) {
          const int id = tab.rel[slot][s][t];
          kp[s][t] = id < 0 ? nullptr : kb + (std::size_t) id * 32;
        }
      for (const auto &pr : pl) {
        double *const *y = ytab + 8 * (std::size_t) pr.first;
        const double *const *x = xtab + 8 * (std::size_t) pr.second;
        for (int t = 0; t < 8; ++t) {
          if (!y[t]) continue;
          double *yt = y[t] + yo;
#if defined(__AVX512F__)
          // accumulators stay in registers over the 8 sources; separate accumulators for
          // the two product terms keep the FMA chains short
          __m512d ar0 = _mm512_loadu_pd(yt), ar1 = _mm512_loadu_pd(yt + 8);
          __m512d ai0 = _mm512_loadu_pd(yt + 16), ai1 = _mm512_loadu_pd(yt + 24);
          __m512d br0 = _mm512_setzero_pd(), br1 = br0, bi0 = br0, bi1 = br0;
          for (int s = 0; s < 8; ++s) {
            if (!x[s] || !kp[s][t]) continue;
            const double *k = kp[s][t], *xs = x[s] + xo;
            const __m512d kr0 = _mm512_loadu_pd(k), kr1 = _mm512_loadu_pd(k + 8);
            const __m512d ki0 = _mm512_loadu_pd(k + 16), ki1 = _mm512_loadu_pd(k + 24);
            const __m512d xr0 = _mm512_loadu_pd(xs), xr1 = _mm512_loadu_pd(xs + 8);
            const __m512d xi0 = _mm512_loadu_pd(xs + 16), xi1 = _mm512_loadu_pd(xs + 24);
            ar0 = _mm512_fmadd_pd(kr0, xr0, ar0);
            ar1 = _mm512_fmadd_pd(kr1, xr1, ar1);
            br0 = _mm512_fnmadd_pd(ki0, xi0, br0);
            br1 = _mm512_fnmadd_pd(ki1, xi1, br1);
            ai0 = _mm512_fmadd_pd(kr0, xi0, ai0);
            ai1 = _mm512_fmadd_pd(kr1, xi1, ai1);
            bi0 = _mm512_fmadd_pd(ki0, xr0, bi0);
            bi1 = _mm512_fmadd_pd(ki1, xr1, bi1);
          }
          _mm512_storeu_pd(yt, _mm512_add_pd(ar0, br0));
          _mm512_storeu_pd(yt + 8, _mm512_add_pd(ar1, br1));
          _mm512_storeu_pd(yt + 16, _mm512_add_pd(ai0, bi0));
          _mm512_storeu_pd(yt + 24, _mm512_add_pd(ai1, bi1));
#else
          for (int s = 0; s < 8; ++s)
            if (x[s] && kp[s][t]) cmac16(kp[s][t], x[s] + xo, yt);
#endif
        }
      }
    }
  }
}

}    // namespace kifmm
