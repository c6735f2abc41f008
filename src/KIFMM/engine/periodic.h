// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic boundaries (all three dimensions, cubic cell), PVFMM-style:
//  * the tree root is the periodic cell (Options::fixed_root; points are wrapped into it);
//  * interaction lists wrap at every level: the colleague of cell B at offset d is the cell at
//    B + d modulo the number of cells of the level, i.e. an image with a root shift
//    n in {-1,0,1}^3; the root's 27 colleagues are itself. Entries with n = 0 go to the
//    ordinary lists (the free-space passes use them unchanged), entries with n != 0 to the
//    image lists below (near pass with shifted targets, P2L with shifted check surfaces).
//    M2L needs no shift: the colleague slot fixes the geometry (m2l_fft.h);
//  * the images beyond the first shell (|n|_inf >= 2) act through ONE operator at the root:
//    check_i += sum_k R(c_i - e_k) u_k, with u the root's upward equivalent density, c_i its
//    downward check points and R(r) = G_per(r) - sum_{|n|_inf<=1} G(r - nL). The relative
//    positions c_i - e_k lie on the M2L lattice, so R is tabulated there ((2p-1)^3 values).
//    G_per is the Ewald sum (Laplace: tin-foil, k = 0 omitted, with the -pi/(V alpha^2)
//    constant, i.e. a uniform neutralizing background for a net charge; Yukawa: the
//    absolutely convergent lattice sum, by a screened Ewald split or directly).
//  * Laplace only: R is not harmonic (lap R = 4 pi / V, the background), R = H + (2pi/3V)|r|^2.
//    The root operator uses H (harmonic: equivalent densities reproduce it, and the downward
//    equivalent density can carry it); the quadratic part, whose potential
//    (2pi/3V) sum_j q_j |x - y_j|^2 is not harmonic when the net charge is not zero, is added
//    at the targets exactly from the net charge, dipole and second moment of the sources.
#pragma once

#include "interaction_lists.h"
#include "kifmm.h"
#include "octree.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace kifmm {

// MutualPair (a pair of adjacent leaves evaluated once for both): interaction_lists.h

// Image entries of the lists (ImageLists: U, W, X with a nonzero shift, the shifts of V) and
// the periodic evaluation's state that goes with them.
struct PeriodicImageLists : ImageLists {
  // Mutual near field (same source and target points): every unordered pair of U-list
  // entries once, grouped by color (pairs of one color share no leaf: they run in parallel
  // and every target accumulates in the fixed color order, independent of the threads);
  // the U lists are then emptied (the free-space U pass skips them). See periodic_core.h.
  bool mutual = false;
  std::vector<MutualPair> pairs;       // by color
  std::vector<int> color_off;          // pairs of color c: [color_off[c], color_off[c+1])
  std::vector<int> self_leaves;        // leaves with targets (each its own pairs, one round)
  // M2L kernels of the levels 1 and 2 summed over the colleague slots of one source parent
  // (periodic_m2l_top), per operator set and slot mask; kept across evaluations
  struct TopKernel {
    std::shared_ptr<const void> ops;    // keeps the operator set (the key) alive
    uint32_t mask = 0;
    std::vector<double> hat;            // [block][source child * 8 + target child][32]
  };
  std::vector<TopKernel> top_kernels;
  std::size_t bytes() const;
};

// Mutual plan from the periodic lists (U plain entries in `lists`, image ones in `images`):
// returns false (and changes nothing) when the U relation is not symmetric; otherwise fills images.pairs/color_off/self_leaves and empties
// lists.U. Only for trees whose sources and targets are the same points. With `only`
// (distributed evaluation: sources include ghost points), just the leaves marked there (the
// same points in the same order among sources and targets, checked by the caller) and the
// entries between two of them: those entries leave the U lists, the others stay for the
// one-sided passes.
bool plan_mutual_near(const Octree &tree, InteractionLists &lists, PeriodicImageLists &images,
                      const std::vector<char> *only = nullptr);

// Periodic lists of a tree whose root is the periodic cell (see above): build_lists with the
// PeriodicImages policy (interaction_lists.h); resets the mutual plan.
void build_periodic_interaction_lists(const Octree &tree, InteractionLists &lists,
                                      PeriodicImageLists &images);

// Copies of the points wrapped into the cell [center - h, center + h)^3, or with shape (the
// half-widths per axis in units of h, RootBox::shape) into the box [center - h shape, center + h shape).
// dims: the first dims coordinates are wrapped (2: a slab, z kept).
void wrap_into_cell(std::size_t n, const double *xyz, const double center[3], double h,
                    std::vector<double> &out, const double *shape = nullptr, int dims = 3);

// Far-image operator table of the unit root (half-width 1, period 2) for order p:
// r[((i+p-1)*m + j+p-1)*m + k+p-1] = R((i,j,k) * 2*1.05/(p-1)), m = 2p-1. For a root of
// half-width h the physical operator is R_unit / h (Laplace; Yukawa with kappa_unit = kappa h).
// Laplace: R = H + quad |r|^2 (quad = 2 pi / 3V, the uniform background, not harmonic); the
// table holds the harmonic H (reproduced by equivalent densities), the quadratic part is added
// at the targets from the sources' charge, dipole and second moment (exact).
// Rectangular cells (shape: half-widths per axis, largest 1, RootBox::shape): the unit cell has
// periods 2 shape[d] and the table R at the shaped lattice points (i shape[0], j shape[1],
// l shape[2]) * 2*1.05/(p-1).
struct LatticeTable {
  int p = 0;
  std::vector<double> r;
  double quad = 0.0;    // 2 pi / 3V of the unit cell (cube: V = 8, pi / 12) for Laplace, 0 for Yukawa
  double shape[3] = {1.0, 1.0, 1.0};
};
std::shared_ptr<const LatticeTable> lattice_table(const KernelSpec &unit_kernel, int p,
                                                  const double *shape = nullptr);

// The same for charges and dipoles (Laplace, p p p; conventions of evaluate_dipoles; a pair at
// r = 0 skips the bare n = 0 term only), with the second derivatives (hess: 6 per target; pot,
// grad, hess may be null).
void periodic_dipole_direct_sum(const double center[3], double half_width, const double *shape, std::size_t n_src,
                                const double *src_xyz, const double *src_q, const double *src_mu, std::size_t n_trg,
                                const double *trg_xyz, double *pot, double *grad, double *hess);

// Periodic Green's function of the unit cell (period 2; shape: periods 2 shape[d]) and its
// gradient, r in unit coordinates; `regular` subtracts the bare kernel of the n = 0 term (finite at r = 0).
// Laplace includes the background constant. For tests and the reference sum.
void periodic_green_unit(const KernelSpec &unit_kernel, const double r[3], bool regular,
                         double &value, double grad[3], const double *shape = nullptr);

// Exact periodic reference with the engine's conventions (pairs at r = 0 skip only the bare
// n = 0 term; their images and the background are included): Ewald (real space + structure
// factors), O(N M) + O((N + M) K). Cell [center - h, center + h)^3, or with shape the box
// [center - h shape, center + h shape).
void periodic_direct_sum(const KernelSpec &kernel, const double center[3], double half_width,
                         std::size_t n_src, const double *src_xyz, const double *src_q,
                         std::size_t n_trg, const double *trg_xyz, double *pot, double *grad,
                         const double *shape = nullptr);

// Exact doubly periodic reference (periodic in x and y, open in z: Options::periodic_dims = 2;
// Laplace): the Ewald sum of slab_ewald.h over the images in x and y of the cell of half-widths
// h shape[0], h shape[1] centred at center (points wrapped in x and y; z as given), O(N M K).
// Pairs at r = 0 skip only the bare n = 0 term. A net charge needs no background here.
void slab_direct_sum(const double center[3], double half_width, const double *shape, std::size_t n_src,
                     const double *src_xyz, const double *src_q, std::size_t n_trg, const double *trg_xyz,
                     double *pot, double *grad);
// The same gradient from the 3-d Ewald sum (periodic_direct_sum) of the slab's cell stretched in
// z to leave a vacuum of 4 times the longest x-y edge between the images, with the slab
// correction of Yeh and Berkowitz and the net-charge terms of Ballenegger, Arnold and Cerda
// (grad_z += 4 pi / V sum_j q_j (z_j - z_i)): O(N M) + O((N + M) K), equal to slab_direct_sum
// to ~1e-11 (tested); the error check uses it for large systems.
void slab_gradient_via_3d(const double center[3], double half_width, const double *shape, std::size_t n_src,
                          const double *src_xyz, const double *src_q, std::size_t n_trg, const double *trg_xyz,
                          double *grad);

}    // namespace kifmm
