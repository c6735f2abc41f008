// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The tree of an N-body evaluation from what the caller asks for (kifmm.h: plan_tree,
// choose_tree_from_points), on top of the two choose_tree of calibration.cpp.
#include "kifmm.h"

namespace kifmm {

namespace {
// the single-level grid is chosen with the tree when asked for (in periodic cells the octree
// does not fit, only grids are candidates: choose_tree)
bool grid_is_chosen(const Options &options, const TreeRequest &request)
{
  return options.periodic && request.grid < 0;
}

// one process holds all points, or several ranks up to kLayoutMaxPoints (their stand-in:
// gather_layout); beyond that the uniform choice, the same on every rank
bool from_points_possible(const TreeRequest &request)
{
  return !request.distributed || request.n <= kLayoutMaxPoints;
}
}    // namespace

TreePlan plan_tree(const Options &options, const TreeRequest &request, const Options *current)
{
  TreePlan plan;
  plan.options = options;
  Options &opt = plan.options;
  opt.periodic_grid = options.periodic && request.grid > 0 ? request.grid : 0;
  if (options.periodic && options.periodic_dims == 2) {    // a slab: the grid only
    if (request.leaf_size > 0) opt.leaf_size = request.leaf_size;
    if (request.grid <= 0) {
      plan.uniform = choose_slab_grid(opt.order, request.n, opt.root_shape);
      opt.periodic_grid = plan.uniform.grid;
      // chosen again on the actual occupancies (several ranks: of their stand-in; the grid in
      // use kept until then when the same as before)
      plan.from_points = request.grid < 0 && from_points_possible(request);
      if (plan.from_points && current && current->order == opt.order && current->periodic == opt.periodic &&
          current->periodic_dims == 2 && current->periodic_grid > 0)
        opt.periodic_grid = current->periodic_grid;
    }
    return plan;
  }
  if (request.leaf_size > 0) {
    opt.leaf_size = request.leaf_size;
    return plan;
  }
  const bool choose_grid = grid_is_chosen(options, request);
  plan.uniform = choose_tree(opt.order, request.n, opt.periodic, choose_grid, opt.periodic ? opt.root_shape : nullptr,
                             opt.near_pair_weight);
  opt.leaf_size = plan.uniform.leaf_size;
  if (choose_grid) opt.periodic_grid = plan.uniform.grid;
  if (!from_points_possible(request)) return plan;
  plan.from_points = true;
  if (current && current->order == opt.order && current->cache_dir == opt.cache_dir &&
      current->periodic == opt.periodic) {
    opt.leaf_size = current->leaf_size;
    if (choose_grid) opt.periodic_grid = current->periodic_grid;
  }
  return plan;
}

TreeChoice choose_tree_from_points(const KernelSpec &kernel, const TreeRequest &request, Options &options,
                                   std::size_t n, const double *xyz)
{
  const TreeChoice c = choose_tree(kernel, options, n, xyz);
  options.leaf_size = c.leaf_size;
  if (grid_is_chosen(options, request)) options.periodic_grid = c.grid;
  return c;
}

TreeChoice choose_tree_from_layout(const KernelSpec &kernel, const TreeRequest &request, Options &options,
                                   const PointLayout &layout)
{
  const TreeChoice c = choose_tree(kernel, layout.model, layout.n, layout.xyz.data());
  options.leaf_size = c.leaf_size;
  if (grid_is_chosen(options, request)) options.periodic_grid = c.grid;
  return c;
}

}    // namespace kifmm
