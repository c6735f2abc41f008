#include "m2l_fft.h"

#include "surface.h"

#include <fftw3.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

namespace kifmm {

namespace {
std::mutex &fftw_mutex()
{
  static std::mutex m;
  return m;
}

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
  hat.assign((std::size_t) kM2LKernels * 2 * nfreq, 0.0);
  const double dx = p > 1 ? 2.0 * kRadiusInner / (p - 1) : 0.0;
  const double norm = 1.0 / (double(n) * n * n);
  double *grid;
  fftw_complex *spec;
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(fftw_mutex());
    grid = fftw_alloc_real((std::size_t) n * n * n);
    spec = fftw_alloc_complex(nfreq);
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
              const double rx = 2.0 * ox + i * dx, ry = 2.0 * oy + j * dx, rz = 2.0 * oz + l * dx;
              const int gi = (i + n) % n, gj = (j + n) % n, gl = (l + n) % n;
              grid[((std::size_t) gi * n + gj) * n + gl] = k.g(rx * rx + ry * ry + rz * rz);
            }
        fftw_execute_dft_r2c(plan, grid, spec);
        double *re = hat.data() + (std::size_t) id * 2 * nfreq, *im = re + nfreq;
        for (int f = 0; f < nfreq; ++f) {
          re[f] = spec[f][0] * norm;
          im[f] = spec[f][1] * norm;
        }
      }
  std::lock_guard<std::mutex> lock(fftw_mutex());
  fftw_destroy_plan(plan);
  fftw_free(grid);
  fftw_free(spec);
}

M2LTransform::M2LTransform(int p) : p_(p), n_(m2l_grid_n(p)), nfreq_(m2l_nfreq(p))
{
  const std::vector<int> lat = surface_lattice(p);
  surf2grid_.resize(lat.size() / 3);
  for (std::size_t m = 0; m < surf2grid_.size(); ++m)
    surf2grid_[m] = (lat[3 * m] * n_ + lat[3 * m + 1]) * n_ + lat[3 * m + 2];
  // one pair of plans per order for the whole process
  static std::map<int, std::pair<fftw_plan, fftw_plan>> plans;
  std::lock_guard<std::mutex> lock(fftw_mutex());
  auto it = plans.find(p);
  if (it == plans.end()) {
    double *g = fftw_alloc_real((std::size_t) n_ * n_ * n_);
    fftw_complex *s = fftw_alloc_complex(nfreq_);
    fftw_plan f = fftw_plan_dft_r2c_3d(n_, n_, n_, g, s, FFTW_ESTIMATE);
    fftw_plan b = fftw_plan_dft_c2r_3d(n_, n_, n_, s, g, FFTW_ESTIMATE);
    fftw_free(g);
    fftw_free(s);
    if (!f || !b) throw std::runtime_error("kifmm: FFTW plan creation failed");
    it = plans.emplace(p, std::make_pair(f, b)).first;
  }
  plan_fwd_ = (void *) it->second.first;
  plan_bwd_ = (void *) it->second.second;
}

M2LTransform::Workspace::Workspace(const M2LTransform &t)
{
  const int n = m2l_grid_n(t.p());
  grid = fftw_alloc_real((std::size_t) n * n * n);
  spec = (double *) fftw_alloc_complex(t.nfreq());
}

M2LTransform::Workspace::~Workspace()
{
  fftw_free(grid);
  fftw_free(spec);
}

void M2LTransform::forward(const double *equiv, double *hat, Workspace &w) const
{
  std::memset(w.grid, 0, sizeof(double) * n_ * n_ * n_);
  for (std::size_t m = 0; m < surf2grid_.size(); ++m) w.grid[surf2grid_[m]] = equiv[m];
  fftw_execute_dft_r2c((fftw_plan) plan_fwd_, w.grid, (fftw_complex *) w.spec);
  double *re = hat, *im = hat + nfreq_;
  for (int f = 0; f < nfreq_; ++f) {
    re[f] = w.spec[2 * f];
    im[f] = w.spec[2 * f + 1];
  }
}

void M2LTransform::inverse_add(const double *hat, double *check, double scale, Workspace &w) const
{
  const double *re = hat, *im = hat + nfreq_;
  for (int f = 0; f < nfreq_; ++f) {
    w.spec[2 * f] = re[f];
    w.spec[2 * f + 1] = im[f];
  }
  fftw_execute_dft_c2r((fftw_plan) plan_bwd_, (fftw_complex *) w.spec, w.grid);
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
}    // namespace

void m2l_hadamard_parent(int nfreq, const double *kernels, int n_groups, const int *group_slot,
                         const double *const (*x)[8], double *const y[8])
{
  const ChildOffsetTable &tab = child_offsets();
  constexpr int kBlock = 64;
  for (int f0 = 0; f0 < nfreq; f0 += kBlock) {
    const int nb = std::min(kBlock, nfreq - f0);
    for (int g = 0; g < n_groups; ++g) {
      const int slot = group_slot[g];
      for (int s = 0; s < 8; ++s) {
        const double *xs = x[g][s];
        if (!xs) continue;
        const double *__restrict xr = xs + f0, *__restrict xi = xs + nfreq + f0;
        for (int t = 0; t < 8; ++t) {
          const int kidx = tab.rel[slot][s][t];
          if (kidx < 0 || !y[t]) continue;
          const double *__restrict kr = kernels + (std::size_t) kidx * 2 * nfreq + f0;
          const double *__restrict ki = kr + nfreq;
          double *__restrict yr = y[t] + f0, *__restrict yi = y[t] + nfreq + f0;
#pragma omp simd
          for (int f = 0; f < nb; ++f) {
            const double a = kr[f], b = ki[f], c = xr[f], d = xi[f];
            yr[f] += a * c - b * d;
            yi[f] += a * d + b * c;
          }
        }
      }
    }
  }
}

}    // namespace kifmm

