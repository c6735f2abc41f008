// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// M2L as a convolution on the regular (2p)^3 lattice (FFTW r2c/c2r).
//
// The upward-equivalent surface of a source cell and the downward-check surface of a target
// cell at the same level (both radius 1.05) lie on one lattice of spacing 2*1.05/(p-1) (unit
// box): check(t) = sum_s G(c_t - c_s + (i_t - i_s) dx) equiv(s). With c_t - c_s = 2 d,
// d in [-3,3]^3 not adjacent (316 offsets), the kernel sampled at i_t - i_s in [-(p-1),p-1]^3
// and padded to n = 2p is transformed once per operator set (m2l_kernel_transforms); each
// source cell's density is transformed once, products accumulate per target in frequency
// space, and each target is transformed back once.
//
// Frequency data are split (re[nfreq], im[nfreq]) so the complex multiply-add vectorizes.
// The products are blocked over frequencies (see m2l_accumulate).
#pragma once

#include "kernel_scaling.h"

#include <mutex>
#include <utility>
#include <vector>

namespace kifmm {

// FFTW's planner is not thread-safe: every plan creation/destruction in the engine holds this.
std::mutex &fftw_mutex();

inline int m2l_grid_n(int p) { return 2 * p; }
// Complex frequencies of the r2c transform, and the storage stride (padded to 16).
inline int m2l_nfreq_raw(int p) { const int n = 2 * p; return n * n * (n / 2 + 1); }
inline int m2l_nfreq(int p) { return (m2l_nfreq_raw(p) + 15) / 16 * 16; }
constexpr int kM2LKernels = 316;

// Compact index 0..315 of a non-adjacent offset d in [-3,3]^3, or -1 if adjacent/out of range.
int m2l_offset_index(int dx, int dy, int dz);

// Transforms of the 316 M2L kernels, each divided by n^3 (normalizes the inverse FFT), stored
// block-major: chunk (b, kernel) of 32 doubles at ((b * 316) + kernel) * 32.
void m2l_kernel_transforms(const UnitKernel &k, int p, std::vector<double> &hat, int &nfreq);

// Per-order FFT machinery (plans are created once per process and order, thread-safe).
class M2LTransform {
 public:
  explicit M2LTransform(int p);
  int p() const { return p_; }
  int nfreq() const { return nfreq_; }
  // Scratch buffers for one thread.
  struct Workspace {
    double *grid = nullptr;    // p x p x n reals: the lines of the lattice that hold surface points
    double *spec = nullptr;    // nfreq complex (interleaved), n x n x (n/2+1)
    explicit Workspace(const M2LTransform &t);
    ~Workspace();
    Workspace(const Workspace &) = delete;
    Workspace &operator=(const Workspace &) = delete;
  };
  // Spectra are stored in 16-frequency chunks of 32 doubles (16 re, then 16 im); chunk b of
  // a cell's spectrum is at hat + b * stride (block-major arrays over all cells of a level).
  // equivalent density on the surface -> spectrum
  void forward(const double *equiv, double *hat, std::size_t stride, Workspace &w) const;
  // check potential on the surface += scale * inverse(spectrum)
  void inverse_add(const double *hat, std::size_t stride, double *check, double scale, Workspace &w) const;

 private:
  int p_, n_, nfreq_, nraw_;
  std::vector<int> surf2grid_;    // surface point -> index in the p x p x n real lines
  // The surface lattice fills only the corner [0,p)^3 of the (2p)^3 grid, and only that corner
  // of the inverse is read: the 3-d transforms run as three passes of 1-d transforms, each over
  // the lines that are not zero (forward) or are needed (inverse): p^2, p (n/2+1) and
  // n (n/2+1) lines instead of n^2, n (n/2+1) and n (n/2+1) (about 0.6 of the work).
  // fwd_: r2c along z, c2c along y, c2c along x; bwd_: the reverse.
  void *fwd_[3], *bwd_[3];
};

// Blocked frequency-space products (PVFMM / exafmm-t style). pairs[slot] lists (target
// parent, source parent) index pairs whose source parent is the target parent's colleague at
// that slot; ytab/xtab hold 8 child spectra per parent (null: child absent, or without
// targets / sources). For each 16-frequency block in [block_begin, block_end) and each slot,
// the 8x8 child-child kernel block stays in L1 while all parent pairs of that slot are
// processed: y[t] += K(t - s) .* x[s] for non-adjacent (t, s). Blocks are disjoint in y, so
// threads can own blocks; the per-target order is fixed (deterministic).
void m2l_parent_pairs(int nfreq, const double *kernels, int block_begin, int block_end,
                      const std::vector<std::pair<int, int>> *pairs, const double *const *xtab,
                      std::size_t xstride, double *const *ytab, std::size_t ystride);

}    // namespace kifmm
