// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic (p p p) evaluation on ONE level of k^3 cubic cells (k >= 3 per side), or in a
// rectangular periodic cell kx x ky x kz cells (grid_cells_per_axis), the cheaper choice for
// small N (about 1e3 .. 3e4 atoms, see cost_model.h): the octree's 4 or 8 leaves per side leave
// either too many atoms per leaf (near field) or too many M2L translations; 5, 6, 7 ... per
// side fill the gap. Laplace and Yukawa.
//   near field : every cell with itself and the cells within m_d along each axis d
//                (grid_near_depth: m = 1 1 1, the 26 neighbours, for nearly cubic cells; deeper
//                along the short axes of stretched cells), images included (with few cells
//                along an axis, its own images or one cell met at several shifts), pair by pair
//                for both sides when sources = targets;
//   far field  : ALL other images of all cells through one convolution. For a target cell t
//                and a source cell s, every image s + k n outside t's near field
//                (|s_d + k_d n_d - t_d| > m_d along some axis d) acts through the ordinary M2L
//                (its equivalent surface is well separated from t's check surface), and these
//                images are summed into one kernel per offset class D = t - s mod k:
//                  K_D(r) = G_per(r) - sum_{n: |D_d + k_d n_d| <= m_d} G(r + 2k n h) - quad |r|^2
//                sampled on the M2L lattice (G_per: the Ewald sum of the cell, Laplace tin-foil
//                with the background, quad |r|^2 its non-harmonic part, added exactly at the
//                targets from the moments as in the octree path; Yukawa: the screened lattice
//                sum, quad = 0). Check(t) = sum_s K_{t-s}
//                (*) equiv(s) is a circular convolution over the cells: a DFT of size k^3 per
//                surface frequency, so the M2L costs O(k^3 log k) per frequency instead of
//                O(k^6);
//   P2M / L2P  : the octree's operators at the cell size.
// No M2M, L2L or root operator: the far images are all in K_D.
#pragma once

#include "kifmm.h"
#include "m2l_fft.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstddef>
#include <memory>
#include <vector>

namespace kifmm {

// Frequencies per cell in the grid's buffers (GridKernel::nfreq): the r2c spectrum of the M2L
// lattice rounded up to an odd number of 16-frequency blocks. The DFT over the cells reads one
// block of every cell, nfreq apart; an even number of blocks makes that stride a multiple of
// 512 bytes (at p = 8, 9 x 4096), so the cells' blocks fall into a few cache sets and evict
// each other (with such a stride the convolution over 24 x 3 x 3 cells takes 3x as long as over
// 25 x 3 x 3).
inline int grid_row_stride(int p)
{
  const int blocks = (m2l_nfreq_raw(p) + 15) / 16;
  return 16 * (blocks % 2 ? blocks : blocks + 1);
}

// Kernels of the unit grid (cell half-width 1, period 2k) for order p; the physical operator
// at cell half-width h is K / h (Laplace is homogeneous). hat[w * nfreq + f]: cell frequency w
// (DFT of the offset class D = t - s mod k), surface frequency f (r2c of the (2p)^3 lattice,
// f = nraw .. nfreq-1 zero; nfreq = grid_row_stride(p)), divided by (2p)^3 k^3 (normalizes
// both inverse transforms).
struct GridKernel {
  int k = 0, p = 0, nraw = 0, nfreq = 0;    // k: cells along the first axis (cubes: per side)
  int cells[3] = {0, 0, 0};                 // cells per axis
  double cell_shape[3] = {1.0, 1.0, 1.0};   // a cell's half-widths (largest 1)
  bool slab = false;    // periodic in x and y, open in z (slab_ewald.h): a linear convolution in z
  int nz = 0;           // slots along z of the convolution: cells[2], or 2 cells[2] (zero padded) for a slab
  std::size_t slots() const { return (std::size_t) cells[0] * cells[1] * nz; }
  // slot of cell (a0 ky + a1) kz + a2 in the convolution buffer
  std::size_t slot(int b) const
  {
    const int kz = cells[2];
    return (std::size_t) (b / kz) * nz + b % kz;
  }
  std::vector<std::complex<double>> hat;
  double quad = 0.0;    // quadratic part of G_per in unit-grid coordinates: 2 pi / (3 V), V = (2k)^3 for cubes
  void *plan_fwd = nullptr, *plan_bwd = nullptr;    // DFTs over the cells of 16 frequency rows
  GridKernel() = default;
  GridKernel(const GridKernel &) = delete;
  GridKernel &operator=(const GridKernel &) = delete;
  ~GridKernel();
  std::size_t bytes() const { return hat.size() * sizeof(std::complex<double>); }
};

// Cell index (a0 ky + a1) kz + a2 of a point of the cell [c - H shape, c + H shape) in the grid
// of cells[0] x cells[1] x cells[2] cells (points on the upper faces or outside are clamped into
// the boundary cells; shape null: a cube).
inline int grid_cell_index(const double x[3], const double c[3], double H, const double *shape, const int cells[3])
{
  int a[3];
  for (int d = 0; d < 3; ++d) {
    const double hd = H * (shape ? shape[d] : 1.0), w = 2.0 * hd / cells[d];
    a[d] = std::min(cells[d] - 1, std::max(0, (int) std::floor((x[d] - (c[d] - hd)) / w)));
  }
  return (a[0] * cells[1] + a[1]) * cells[2] + a[2];
}
inline int grid_cell_index(const double x[3], const double c[3], double H, int k)
{
  const int cells[3] = {k, k, k};
  return grid_cell_index(x, c, H, nullptr, cells);
}

// Representative in (-k/2, k/2] of the cell offset class a mod k (the nearest image)
inline int grid_class_representative(int a, int k)
{
  const int r = ((a % k) + k) % k;
  return 2 * r <= k ? r : r - k;
}

// The cell at offset (dx, dy, dz) of cell b, periodically; sh: the root shift of that image
// (floor of the offset cell's index over the cells along the axis: -1, 0 or 1 for offsets
// within one period).
inline int grid_neighbour_cell(int b, const int cells[3], int dx, int dy, int dz, signed char sh[3])
{
  const int a[3] = {b / (cells[1] * cells[2]) + dx, (b / cells[2]) % cells[1] + dy, b % cells[2] + dz};
  int w[3];
  for (int d = 0; d < 3; ++d) {
    const int q = a[d] >= 0 ? a[d] / cells[d] : -((cells[d] - 1 - a[d]) / cells[d]);
    sh[d] = (signed char) q;
    w[d] = a[d] - q * cells[d];
  }
  return (w[0] * cells[1] + w[1]) * cells[2] + w[2];
}
// The near field's cell offsets (dx, dy, dz), |d_a| <= m_a (grid_near_depth), in lexicographic
// order: offset i and offset size - 1 - i are opposite, the middle one is 0 0 0.
inline std::vector<std::array<int, 3>> grid_near_offsets(const int m[3])
{
  std::vector<std::array<int, 3>> o;
  for (int x = -m[0]; x <= m[0]; ++x)
    for (int y = -m[1]; y <= m[1]; ++y)
      for (int z = -m[2]; z <= m[2]; ++z) o.push_back({x, y, z});
  return o;
}
inline int grid_neighbour_cell(int b, int k, int dx, int dy, int dz, signed char sh[3])
{
  const int cells[3] = {k, k, k};
  return grid_neighbour_cell(b, cells, dx, dy, dz, sh);
}

// Cached per (kernel, cells, cell shape, p) in the process (a few tenths of a second to
// compute at p = 6, k = 5). `unit`: the kernel of the unit cell (half-width 1), Laplace or
// Yukawa with kappa * H (H the largest half-width of the periodic cell), as lattice_table
// (periodic.h). cell_shape: the half-widths of a cell (largest 1; null: cubic cells), whose
// largest is 1 in unit-grid coordinates.
std::shared_ptr<const GridKernel> periodic_grid_kernel(const KernelSpec &unit, const int cells[3], int p,
                                                       const double *cell_shape, bool slab = false);
inline std::shared_ptr<const GridKernel> periodic_grid_kernel(const KernelSpec &unit, int k, int p)
{
  const int cells[3] = {k, k, k};
  return periodic_grid_kernel(unit, cells, p, nullptr);
}

// Offset-weighted kernels of the periodic virial (Laplace and Yukawa in p p p, Laplace in slabs): for the offset class D and
// component a, sum over the far images n of (D_n)_a G(r_n), D_n = c_t - c_s - n L the offset of
// the cells' centres and r_n the separation of the points, as P_a(r) - zeta_a G_per(r) with
// P_a(r) = sum_n (r + n L)_a G(r + n L) (Ewald: real-space (r_n)_a erfc(alpha r_n) / r_n, reciprocal
// (4 pi / V) k_a exp(-k^2/4alpha^2) (2/k^4 + 1/(2 alpha^2 k^2)) sin(k.r); grad P_a = e_a G_per + the
// strain derivative of G_per) and zeta = r - D_n (within the cells); less the non-harmonic part
// -(2 pi / 5 V) zeta_a |zeta|^2, which the caller adds at the targets. Degree 0: the tables are
// the physical kernels at any cell size. Yukawa (`unit` as periodic_grid_kernel): k^2 + kappa^2
// for k^2 in the reciprocal terms' exp and powers, no background part. Slab (p p f): the images
// over the x-y lattice only, no non-harmonic part (slab_kernel_values). Cached like
// periodic_grid_kernel.
struct GridMomentKernels {
  std::shared_ptr<const GridKernel> a[3];
  std::size_t bytes() const { return a[0]->bytes() + a[1]->bytes() + a[2]->bytes(); }
};
std::shared_ptr<const GridMomentKernels> periodic_grid_moment_kernels(const KernelSpec &unit, const int cells[3], int p,
                                                                      const double *cell_shape, bool slab = false);

// In place on the frequencies [f0, f1) (multiples of 16) of z[cell * nfreq + f] (cell-major,
// so that each cell's spectrum is contiguous): z <- IDFT(hat .* DFT(z)) over the cells.
// Thread-safe (frequencies are independent).
void grid_convolve(const GridKernel &g, std::complex<double> *z, int f0, int f1);

// Allocation with FFTW's alignment (the plans are made for it).
std::complex<double> *grid_alloc(std::size_t n);
void grid_free(std::complex<double> *z);

// The spectra of all cells, kept between evaluations (tens of MB: a new allocation would
// page-fault at every evaluation); grows only.
class GridBuffer {
 public:
  GridBuffer() = default;
  GridBuffer(const GridBuffer &) = delete;
  GridBuffer &operator=(const GridBuffer &) = delete;
  ~GridBuffer() { grid_free(z_); }
  std::complex<double> *get(std::size_t n)
  {
    if (n > size_) {
      grid_free(z_);
      z_ = nullptr;
      size_ = 0;
      z_ = grid_alloc(n);
      size_ = n;
    }
    return z_;
  }
  std::size_t bytes() const { return size_ * sizeof(std::complex<double>); }

 private:
  std::complex<double> *z_ = nullptr;
  std::size_t size_ = 0;
};

}    // namespace kifmm
