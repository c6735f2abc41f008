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
// The products are blocked as in PVFMM/exafmm-t: for a target parent and each of its 26
// colleagues, the 8 x 8 child-child interactions run over one frequency block at a time.
#pragma once

#include "kernel_scaling.h"

#include <vector>

namespace kifmm {

inline int m2l_grid_n(int p) { return 2 * p; }
inline int m2l_nfreq(int p) { const int n = 2 * p; return n * n * (n / 2 + 1); }
constexpr int kM2LKernels = 316;

// Compact index 0..315 of a non-adjacent offset d in [-3,3]^3, or -1 if adjacent/out of range.
int m2l_offset_index(int dx, int dy, int dz);

// Transforms of the 316 M2L kernels, each divided by n^3 (normalizes the inverse FFT).
void m2l_kernel_transforms(const UnitKernel &k, int p, std::vector<double> &hat, int &nfreq);

// Per-order FFT machinery (plans are created once per process and order, thread-safe).
class M2LTransform {
 public:
  explicit M2LTransform(int p);
  int p() const { return p_; }
  int nfreq() const { return nfreq_; }
  // Scratch buffers for one thread.
  struct Workspace {
    double *grid = nullptr;    // n^3 reals
    double *spec = nullptr;    // nfreq complex (interleaved)
    explicit Workspace(const M2LTransform &t);
    ~Workspace();
    Workspace(const Workspace &) = delete;
    Workspace &operator=(const Workspace &) = delete;
  };
  // equivalent density on the surface -> split spectrum (2*nfreq doubles)
  void forward(const double *equiv, double *hat, Workspace &w) const;
  // check potential on the surface += scale * inverse(hat)
  void inverse_add(const double *hat, double *check, double scale, Workspace &w) const;

 private:
  int p_, n_, nfreq_;
  std::vector<int> surf2grid_;
  void *plan_fwd_, *plan_bwd_;
};

// For a target parent: y[t] (+)= sum over colleague groups g (slot o_g, 8 source children
// x[g][s], null when absent) of K(d) .* x[g][s], d = child offset of t relative to s at the
// child level. y[t] null: child absent or without targets. Blocked over frequencies.
void m2l_hadamard_parent(int nfreq, const double *kernels, int n_groups, const int *group_slot,
                         const double *const (*x)[8], double *const y[8]);

}    // namespace kifmm
