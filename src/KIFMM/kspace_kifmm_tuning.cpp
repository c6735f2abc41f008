// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Tuning the tree of kspace_style kifmm by timing (kspace_modify kifmm tune yes, the default):
// after the first evaluation of a run, whose tree comes from the cost model and whose order is
// checked against the requested accuracy there, the next evaluations time the trees near it
// (kifmm::TreeTuner: octrees of neighbouring leaf sizes and, when the grid is chosen with the
// tree, single-level grids) and the fastest is kept for the rest of the run. Every tree has the
// same order, so every evaluation's forces are used. A given leaf size or grid is not tuned.
#include "kspace_kifmm.h"

#include "comm.h"
#include "update.h"

#include <mpi.h>

using namespace LAMMPS_NS;

namespace {
std::string tree_text(const kifmm::TreeChoice &t, const std::string &grid_cells)
{
  return t.grid > 0 ? "single-level grid of " + grid_cells + " cells" : "leaf size " + std::to_string(t.leaf_size);
}
}    // namespace

// before an evaluation: tuning starts at the second evaluation of a run, once the order is
// settled (one rank: the trees modelled on its atoms; several: on the stand-in of all ranks'
// atoms, kifmm::gather_layout, or beyond its size on uniformly spread atoms, the same on every
// rank); the evaluator of the tree to time next
void KSpaceKIFMM::select_tuned_tree()
{
  if (tune_pending && !verify_pending && !tree_choice_pending) {
    tune_pending = false;
    if (distributed()) {
      const kifmm::PointLayout layout =
          kifmm::gather_layout(engine->kernel(), engine_options, strength.size(), xyz.data(), *kcomm);
      tuner = kifmm::TreeTuner(engine->kernel(), tree_request, engine_options, layout);
    } else {
      tuner = kifmm::TreeTuner(engine->kernel(), tree_request, engine_options, strength.size(), xyz.data());
    }
  }
  if (!tuner.tuning()) return;
  tuner.select(engine);
  engine_options = engine->options();
}

// after an evaluation (seconds: its time without operator setup): the time recorded (the
// slowest rank's). With an order from the accuracy, the first evaluation of each new tree has its
// error measured on the atoms as at the start of the run; a tree that falls short is dropped and
// the evaluation done again on the first tree.
void KSpaceKIFMM::tune_tree(double seconds, bool want_potential, double &comm_time, std::size_t &nsrc)
{
  if (tuner.tuning() && tuner.new_tree() && estimated_error >= 0) {
    const MeasuredError m = measure_error(kset.check_samples > 0 ? kset.check_samples : verify_samples);
    const double target = verify_margin * kset.accuracy;
    if (m.worst() > target) {
      if (comm->me == 0)
        utils::logmesg(lmp, "  KIFMM tuning: {} measured {:.3e} on these atoms > {:.3g} (3/4 of the request): not used\n",
                       tree_text(kifmm::TreeChoice{engine_options.leaf_size, 0, 0.0, engine_options.periodic_grid},
                                 grid_cells_text(engine_options)),
                       m.worst(), target);
      tuner.reject(engine);
      engine_options = engine->options();
      evaluate_points(want_potential, comm_time, nsrc);
      if (!tuner.tuning()) finish_tuning();
      return;
    }
  }
  if (!tuner.tuning()) return;
  double slowest = seconds;
  MPI_Allreduce(&seconds, &slowest, 1, MPI_DOUBLE, MPI_MAX, world);
  tuner.record(slowest);
  if (!tuner.tuning()) finish_tuning();
}

void KSpaceKIFMM::finish_tuning()
{
  const kifmm::TreeChoice t = tuner.finish(engine);
  engine_options = engine->options();
  const auto &timed = tuner.timed();
  const kifmm::TreeChoice &first = timed.front().tree;    // the modelled choice, whose error was measured
  const bool changed = first.leaf_size != t.leaf_size || first.grid != t.grid;
  // the error was measured on the first tree: measured again on this one at the next evaluation
  if (changed && estimated_error >= 0) verify_pending = true;
  if (comm->me != 0) return;
  std::string times;
  for (const auto &c : timed)
    times += fmt::format("{}{} {}", times.empty() ? "" : ", ",
                         c.tree.grid > 0 ? "grid " + grid_cells_text(kifmm::tree_options(engine_options, c.tree))
                                         : "leaf " + std::to_string(c.tree.leaf_size),
                         c.rejected ? std::string("not used (error)") : fmt::format("{:.4g} s", c.least));
  double least = timed.front().least;
  for (const auto &c : timed)
    if (c.tree.grid == t.grid && c.tree.leaf_size == t.leaf_size) least = c.least;
  const std::string now = tree_text(t, grid_cells_text(engine_options));
  const std::string modelled = tree_text(first, grid_cells_text(kifmm::tree_options(engine_options, first)));
  utils::logmesg(lmp,
                 "  KIFMM tree tuned on {} evaluations (to step {}): {} ({}; least time per "
                 "evaluation: {})\n",
                 tuner.evaluations(), update->ntimestep, now,
                 changed ? fmt::format("{:.2f} times as fast as the modelled choice, {}",
                                       timed.front().least / least, modelled)
                         : std::string("the modelled choice kept"),
                 times);
}
