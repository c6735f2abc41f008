// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Periodic boundaries of kspace_style kifmm (boundary p p p, any orthogonal box; p p f): checks at
// init, the periodic cell handed to the engine at every evaluation (boxes that change size or
// shape), the tree or grid that fits the box, the virial. The lattice sums themselves are in the
// engine (engine/periodic.h, engine/periodic_grid.h).
#include "kspace_kifmm.h"

#include "comm.h"
#include "domain.h"
#include "error.h"
#include "update.h"
#include "utils.h"

#include <algorithm>
#include <cmath>
#include <mpi.h>
#include <string>

using namespace LAMMPS_NS;
using kifmm_lammps::LongRangeKernel;

namespace {
const char *boundary_name(int code)
{
  switch (code) {
    case 0:
      return "p";
    case 1:
      return "f";
    case 2:
      return "s";
    default:
      return "m";
  }
}
}    // namespace

void KSpaceKIFMM::periodic_init()
{
  // 'kspace_modify pressure/scalar yes/no' (KSpace's keyword, made for msm): the constructor
  // leaves -1; a value other than the one written here last is the user's
  if (scalar_pressure_flag != scalar_pressure_written) scalar_pressure_user = scalar_pressure_flag;
  periodic = domain->xperiodic || domain->yperiodic || domain->zperiodic;
  if (!periodic) {    // open boundaries: the full virial tensor is computed
    scalar_pressure_flag = scalar_pressure_written = 0;
    return;
  }
  // p p p, or a slab: p p f (p p s, p p m), periodic in x and y and open in z
  slab = domain->xperiodic && domain->yperiodic && !domain->zperiodic;
  if (!(domain->xperiodic && domain->yperiodic && domain->zperiodic) && !slab)
    error->all(FLERR,
               "kspace_style kifmm: periodic boundaries are not supported for this mixed "
               "periodicity (boundary {} {} {}); use p p p, p p f (a slab: open in z), or f, s or "
               "m in every dimension",
               boundary_name(domain->boundary[0][0]), boundary_name(domain->boundary[1][0]),
               boundary_name(domain->boundary[2][0]));
  if (slab && kset.kernel == LongRangeKernel::Yukawa)
    error->all(FLERR,
               "kspace_style kifmm: kernel yukawa with boundary p p {} (a slab) is not supported; the "
               "doubly periodic sum is implemented for kernels coulomb and gravity",
               boundary_name(domain->boundary[2][0]));
  if (slab && kset.grid == 0)
    error->all(FLERR, "kspace_style kifmm: 'kspace_modify kifmm grid no' (the octree) is not available "
                      "with boundary p p f: a slab uses the single-level grid");
  // gravity in a slab: the doubly periodic sum of the masses converges as it is (far from the
  // layer, the field of a uniform plane of the mean surface density, 2 pi G sigma toward it):
  // there is no background to subtract
  if (slab && kset.kernel == LongRangeKernel::Gravity && kset.jeans)
    error->all(FLERR,
               "kspace_style kifmm: 'kspace_modify kifmm jeans yes' is not available with boundary p p "
               "{} (a slab): the doubly periodic sum of the masses converges without a background (far "
               "from the layer its field is that of a uniform plane, 2 pi G sigma toward it); leave "
               "jeans at no",
               boundary_name(domain->boundary[2][0]));
  if (!slab && kset.kernel == LongRangeKernel::Gravity && !kset.jeans)
    error->all(FLERR,
               "kspace_style kifmm: kernel gravity with periodic boundaries diverges (the mean "
               "density is not zero); use 'kspace_modify kifmm jeans yes' to subtract it "
               "(uniform negative background, Jeans swindle)");
  periodic_cell();
  // the full virial tensor (periodic_tensor_virial) unless 'kspace_modify pressure/scalar yes'
  // asks for the trace only; LAMMPS's flag for scalar-only kspace pressures then makes compute
  // pressure refuse tensor components (thermo pxx, fix npt/nph aniso or tri, fix box/relax
  // aniso, ...) instead of using wrong ones
  scalar_pressure_flag = scalar_pressure_written = scalar_pressure_user == 1 ? 1 : 0;
  // net charge of a slab: no background, the doubly periodic sum of the charges as they are
  if (slab && std::fabs(qsum) > 1.0e-5 && comm->me == 0)
    error->warning(FLERR,
                   "kspace_style kifmm: slab (boundary p p f) with net charge {:.8g}: the doubly "
                   "periodic sum is taken as it is, without a neutralizing background (far from the "
                   "slab the field is that of a uniformly charged plane, 2 pi Q / A on either side); "
                   "kspace_modify slab of ewald/pppm instead adds a uniform background in the "
                   "enlarged box",
                   qsum);
  // net charge: like ewald/pppm, a uniform neutralizing background (energy included)
  else if (kset.kernel == LongRangeKernel::Coulomb && std::fabs(qsum) > 1.0e-5 && comm->me == 0)
    error->warning(FLERR,
                   "kspace_style kifmm: periodic system with net charge {:.8g}: a uniform "
                   "neutralizing background is included (energy -pi Q^2/(2 V alpha^2) as in "
                   "kspace_style ewald/pppm)",
                   qsum);
}

// The box as the periodic cell: center and half-widths (a slab: z from its extent).
void KSpaceKIFMM::periodic_box(double center[3], double half_widths[3]) const
{
  for (int d = 0; d < 3; ++d) {
    center[d] = 0.5 * (domain->boxlo[d] + domain->boxhi[d]);
    half_widths[d] = 0.5 * domain->prd[d];
  }
  if (slab && slab_extent_set) {
    center[2] = 0.5 * (slab_extent[0] + slab_extent[1]);
    half_widths[2] = 0.5 * (slab_extent[1] - slab_extent[0]);
  }
}

// The z extent of a slab's grid covers every atom: the doubly periodic sum does not depend on
// it, but the grid's cells must hold the atoms. Atoms outside the box in z (between
// reneighborings, before LAMMPS loses them with boundary f or moves the shrink-wrapped box)
// widen it beyond the atoms by 5 % of the box height; it is kept while it covers the atoms and
// is at most twice that wider than they need, so that the grid (whose kernels depend on the
// cells' shape) is not made again at every step.
void KSpaceKIFMM::update_slab_extent()
{
  if (!slab) return;
  double lo_hi[2] = {domain->boxlo[2], -domain->boxhi[2]};
  for (std::size_t k = 0; k < index.size(); ++k) {
    lo_hi[0] = std::min(lo_hi[0], xyz[3 * k + 2]);
    lo_hi[1] = std::min(lo_hi[1], -xyz[3 * k + 2]);
  }
  double all[2];
  MPI_Allreduce(lo_hi, all, 2, MPI_DOUBLE, MPI_MIN, world);
  if (!std::isfinite(all[0]) || !std::isfinite(all[1]))
    error->all(FLERR, "kspace_style kifmm: an atom has a non-finite z coordinate (step {})", update->ntimestep);
  const double need[2] = {all[0], -all[1]}, pad = 0.05 * domain->prd[2];
  const bool covers = slab_extent[0] <= need[0] && slab_extent[1] >= need[1];
  const bool snug = slab_extent[0] >= need[0] - 2 * pad && slab_extent[1] <= need[1] + 2 * pad;
  if (slab_extent_set && covers && snug) return;
  const bool inside = need[0] >= domain->boxlo[2] && need[1] <= domain->boxhi[2];
  slab_extent_set = !inside;
  if (inside) return;
  slab_extent[0] = need[0] < domain->boxlo[2] ? need[0] - pad : need[0];
  slab_extent[1] = need[1] > domain->boxhi[2] ? need[1] + pad : need[1];
}

// The periodic cell as the engine's fixed root (largest half-width and the shape).
void KSpaceKIFMM::periodic_root(kifmm::Options &o) const
{
  double c[3], hw[3];
  periodic_box(c, hw);
  const double h = std::max(hw[0], std::max(hw[1], hw[2]));
  o.fixed_root = true;
  o.periodic_dims = slab ? 2 : 3;
  o.root_half_width = h;
  for (int d = 0; d < 3; ++d) {
    o.root_center[d] = c[d];
    o.root_shape[d] = hw[d] == h ? 1.0 : hw[d] / h;
  }
}

// "k^3" for a cube, "kx x ky x kz" for a rectangular box (cells per axis).
std::string KSpaceKIFMM::grid_cells_text(const kifmm::Options &o) const
{
  int c[3];
  kifmm::grid_cells_per_axis(o.periodic_grid, o.root_shape, c);
  if (c[0] == c[1] && c[1] == c[2] && o.periodic_dims == 3) return fmt::format("{}^3", c[0]);
  return fmt::format("{} x {} x {}", c[0], c[1], c[2]);
}

// The octree fits a nearly cubic box; a grid, cells at most kifmm::max_grid_cell_aspect times
// longer than wide (within the grid memory bound).
bool KSpaceKIFMM::periodic_fits(const kifmm::Options &o) const
{
  if (o.periodic_dims == 2) return o.periodic_grid > 0 && kifmm::grid_fits_cell(o.order, o.periodic_grid, o.root_shape, true);
  return o.periodic_grid > 0 ? kifmm::grid_fits_cell(o.order, o.periodic_grid, o.root_shape)
                             : kifmm::octree_fits_cell(o.root_shape);
}

// The tree of these options made to fit the box: the octree needs a box whose longest edge is
// at most kifmm::max_cell_aspect times its shortest, a grid cells whose longest edge is at most
// kifmm::max_grid_cell_aspect times the shortest (the cells per axis in proportion to the edges). What does not fit and was not given is replaced by the
// grid of least modelled cost that fits; what was given and does not fit is an error.
void KSpaceKIFMM::fit_periodic_box(kifmm::Options &o)
{
  if (periodic_fits(o)) return;
  const double *L = domain->prd;
  if (o.periodic_grid == 0 && kset.grid == 0)
    error->all(FLERR,
               "kspace_style kifmm: 'kspace_modify kifmm grid no' (the octree) needs a nearly cubic "
               "periodic box (longest edge at most {} times the shortest); the box lengths are "
               "{:.10g} {:.10g} {:.10g} (step {}): use 'grid auto' or a single-level grid",
               kifmm::max_cell_aspect, L[0], L[1], L[2], update->ntimestep);
  if (o.periodic_grid > 0 && kset.grid > 0) {
    int c[3];
    const bool open_z = o.periodic_dims == 2;
    kifmm::grid_cells_per_axis(o.periodic_grid, o.root_shape, c);
    std::string fit;
    int listed = 0;
    for (int k = 3; k <= kifmm::max_grid_cells_long(o.order, o.root_shape) && listed < 6; ++k)
      if (kifmm::grid_fits_cell(o.order, k, o.root_shape, open_z)) {
        fit += (listed++ ? ", " : "") + std::to_string(k);
      }
    error->all(FLERR,
               "kspace_modify kifmm grid {}: in the box of lengths {:.10g} {:.10g} {:.10g} (step {}) "
               "its {} x {} x {} cells are too long for their width (longest edge {:.4g} times the "
               "shortest, at most {}) or exceed the grid memory bound at order {}; grids that fit "
               "(cells along the longest edge): {}",
               kset.grid, L[0], L[1], L[2], update->ntimestep, c[0], c[1], c[2],
               kifmm::grid_cell_aspect(c, o.root_shape), kifmm::max_grid_cell_aspect, o.order,
               fit.empty() ? std::string("none") : fit);
  }
  o.periodic_grid = o.periodic_dims == 2 ? kifmm::choose_slab_grid(o.order, tree_request.n, o.root_shape).grid
                                         : kifmm::choose_tree(o.order, tree_request.n, true, true, o.root_shape).grid;
  // no grid fits (high orders, whose grids are large): the octree in a box within twice the
  // tolerance, its error measured as always when an accuracy is requested
  const double aspect = 1.0 / std::min(o.root_shape[0], std::min(o.root_shape[1], o.root_shape[2]));
  if (o.periodic_grid == 0 && o.periodic_dims == 3 && aspect <= 1.0 + 2 * (kifmm::max_cell_aspect - 1.0) &&
      kset.grid < 0) {
    if (comm->me == 0 && !warned_octree_fallback)
      error->warning(FLERR,
                     "kspace_style kifmm: at order {} no single-level grid fits the "
                     "periodic box of lengths {:.10g} {:.10g} {:.10g}; the octree is used (cells of the "
                     "box's shape, longest edge {:.4g} times the shortest: larger errors at this order)",
                     o.order, L[0], L[1], L[2], aspect);
    warned_octree_fallback = true;
    return;
  }
  if (o.periodic_grid == 0)
    error->all(FLERR,
               "kspace_style kifmm: no single-level grid (cells at most {} times longer than wide) "
               "fits the periodic box of lengths {:.10g} {:.10g} {:.10g} (step {}) within the grid "
               "memory bound at order {} (an octree needs the longest edge at most {} times the shortest)",
               kifmm::max_grid_cell_aspect, L[0], L[1], L[2], update->ntimestep, o.order, kifmm::max_cell_aspect);
}

// The box is the periodic cell, handed to the engine at every evaluation so that fix deform,
// fix npt and change_box are followed. A box whose shape changed so that the tree in use no
// longer fits it switches to one that does (fit_periodic_box).
void KSpaceKIFMM::periodic_cell()
{
  if (!engine) return;
  double center[3], hw[3];
  periodic_box(center, hw);
  // yukawa on a grid chosen by the cost model (grid auto): its grid kernels depend on kappa
  // times the box length and would be computed again (0.1-0.5 s) at every change of the box
  // size: the first change switches to the octree (same order and leaf size) where it fits
  const kifmm::Options &o = engine->options();
  const double h = std::max(hw[0], std::max(hw[1], hw[2]));
  const double shape[3] = {hw[0] / h, hw[1] / h, hw[2] / h};
  if (kset.kernel == LongRangeKernel::Yukawa && kset.grid < 0 && o.periodic_grid > 0 && o.fixed_root &&
      o.root_half_width != h && kifmm::octree_fits_cell(shape)) {
    kifmm::Options octree = o;
    octree.periodic_grid = 0;
    engine = kifmm::make_evaluator(engine->kernel(), octree);
    engine_options = engine->options();
    tuner = kifmm::TreeTuner();    // the trees being timed were grids of this size
    reported_first_evaluation = false;
    if (comm->me == 0)
      utils::logmesg(lmp,
                     "  KIFMM: the box changes size (step {}): kernel yukawa switches from the "
                     "single-level grid to the octree (leaf size {}), whose tables do not depend on "
                     "the box length\n",
                     update->ntimestep, engine_options.leaf_size);
  }
  engine->set_root_box(center, hw);
  if (periodic_fits(engine->options())) return;
  kifmm::Options refit = engine->options();
  const int was_grid = refit.periodic_grid;
  const std::string was = refit.periodic_grid > 0 ? "single-level grid of " + grid_cells_text(refit) + " cells"
                                                  : std::string("octree");
  fit_periodic_box(refit);
  if (refit.periodic_grid == was_grid) return;    // the octree kept: no grid fits (warned)
  engine = kifmm::make_evaluator(engine->kernel(), refit);
  engine_options = engine->options();
  tuner = kifmm::TreeTuner();    // the trees being timed no longer fit
  reported_first_evaluation = false;
  if (comm->me == 0)
    utils::logmesg(lmp,
                   "  KIFMM: the box changes shape (step {}, lengths {:.8g} {:.8g} {:.8g}): the {} no "
                   "longer fits it, the single-level grid of {} cells does\n",
                   update->ntimestep, domain->xprd, domain->yprd, domain->zprd, was, grid_cells_text(refit));
}

// Global virial of the periodic system when only the trace is computed (pressure/scalar yes).
// Coulomb and gravity are homogeneous of degree -1 in all lengths (positions and cell; the
// tin-foil sum and the background term included, and the doubly periodic sum of a slab), so the
// trace of the virial equals the energy: W_xx = W_yy = W_zz = U/3 gives the exact scalar
// pressure for free. Yukawa is not homogeneous: its trace comes from the tensor. The anisotropic
// part is not reported: scalar_pressure_flag = 1 (periodic_init) makes LAMMPS's compute pressure
// stop when tensor components are asked for.
void KSpaceKIFMM::periodic_virial(double e_local, double cf)
{
  double u = 0.0;
  if (kset.kernel == LongRangeKernel::Yukawa) {
    periodic_tensor_virial(cf, true, false);
    u = virial[0] + virial[1] + virial[2];
  } else {
    MPI_Allreduce(&e_local, &u, 1, MPI_DOUBLE, MPI_SUM, world);
  }
  for (int k = 0; k < 6; ++k) virial[k] = 0.0;
  virial[0] = virial[1] = virial[2] = u / 3.0;
}

// The full tensor is computed unless pressure/scalar yes.
bool KSpaceKIFMM::periodic_tensor() const
{
  return periodic && scalar_pressure_flag == 0;
}

// The evaluator of the virial tensor: the engine when it is the single-level grid; next to the
// octree, a grid of the same order (fitting the box; made again when the box changes shape so
// that it no longer fits): the grid of least modelled cost on the atoms' cell occupancies
// (kifmm::model_grids; a Plummer sphere of 1e5 atoms at order 5: 18^3 cells, 1.5 times as fast
// as 7^3, whose near field the cluster fills), on several ranks on the stand-in of all ranks'
// atoms (kifmm::gather_layout); beyond its size one whose cells are about as many as the
// octree's leaves.
kifmm::Evaluator &KSpaceKIFMM::virial_evaluator()
{
  const kifmm::Options &o = engine->options();
  if (o.periodic_grid > 0) {
    virial_engine.reset();
    return *engine;
  }
  double c[3], hw[3];
  periodic_box(c, hw);
  if (virial_engine && virial_engine->options().order == o.order) {
    virial_engine->set_root_box(c, hw);
    if (periodic_fits(virial_engine->options())) return *virial_engine;
  }
  // the atoms the grids are modelled on: this rank's, or the stand-in of all ranks' atoms
  kifmm::PointLayout layout;
  if (distributed()) layout = kifmm::gather_layout(engine->kernel(), o, strength.size(), xyz.data(), *kcomm);
  const kifmm::Options &model = distributed() ? layout.model : o;
  const std::size_t nmodel = distributed() ? (layout.xyz.empty() ? 0 : layout.n) : strength.size();
  const double *xmodel = distributed() ? layout.xyz.data() : xyz.data();
  int best = 0;
  double least = 0;
  if (nmodel > 0)
    for (const kifmm::TreeChoice &g : kifmm::model_grids(engine->kernel(), model, nmodel, xmodel, false))
      if (best == 0 || g.cost < least) best = g.grid, least = g.cost;
  const double want = std::cbrt(std::max(27.0, (double) tree_request.n / std::max(1, o.leaf_size)));
  double dist = 1e300;
  const bool from_atoms = best > 0;
  for (int k = 3; !from_atoms && k <= kifmm::max_grid_cells_long(o.order, o.root_shape); ++k)
    if (kifmm::grid_fits_cell(o.order, k, o.root_shape) && std::fabs(std::log(k / want)) < dist) {
      dist = std::fabs(std::log(k / want));
      best = k;
    }
  if (best == 0)
    error->all(FLERR,
               "kspace_style kifmm: the virial tensor of the periodic box of lengths {:.10g} {:.10g} "
               "{:.10g} needs a single-level grid and none fits at order {}; "
               "'kspace_modify pressure/scalar yes' gives the scalar pressure only",
               domain->xprd, domain->yprd, domain->zprd, o.order);
  kifmm::Options v = o;
  v.periodic_grid = best;
  virial_engine = kifmm::make_evaluator(engine->kernel(), v);
  virial_engine->set_root_box(c, hw);
  if (comm->me == 0)
    utils::logmesg(lmp,
                   "  KIFMM: the virial tensor (pressure components, per-atom virial) is computed on a "
                   "single-level grid of {} cells (order {}) on the steps that need it\n",
                   grid_cells_text(virial_engine->options()), o.order);
  return *virial_engine;
}

// Virial tensor of the periodic system, global (virial[6]) and/or per atom (vatom):
// kifmm::periodic_point_virial, 1/2 sum over all pairs and images of (x_i - x_j - nL)_a F_ij,b,
// without the pairs inside rigid bodies. The trace equals the energy (Coulomb and gravity are
// homogeneous of degree -1).
void KSpaceKIFMM::periodic_tensor_virial(double cf, bool global, bool peratom)
{
  const std::size_t n = index.size();
  std::vector<double> w(6 * n), u(3 * n);
  kifmm::periodic_point_virial(virial_evaluator(), distributed() ? kcomm.get() : nullptr, n, xyz.data(),
                               strength.data(), grad.data(), cf, w.data(), u.data());
  add_body_pair_virial(cf, u.data(), w.data());
  store_point_virial(w, global, peratom);
}

// Per-point virials w (6 per point) into the global virial (summed over ranks) and/or vatom.
void KSpaceKIFMM::store_point_virial(const std::vector<double> &w, bool global, bool peratom)
{
  const std::size_t n = index.size();
  if (global) {
    double v_local[6] = {0, 0, 0, 0, 0, 0};
    for (std::size_t k = 0; k < n; ++k)
      for (int c = 0; c < 6; ++c) v_local[c] += w[6 * k + c];
    MPI_Allreduce(v_local, virial, 6, MPI_DOUBLE, MPI_SUM, world);
  }
  if (peratom)
    for (std::size_t k = 0; k < n; ++k)
      for (int c = 0; c < 6; ++c) vatom[index[k]][c] += w[6 * k + c];
}
