// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The order for a requested accuracy, measured on the points (kifmm.h: raise_order,
// search_order): the policy, with the caller's evaluations and error measurements.
#include "kifmm.h"

#include <cmath>

namespace kifmm {

OrderFound raise_order(OrderTrials &trials, OrderFound at, double target, int max_order)
{
  while (at.error > target && at.order < max_order) {
    const int next = at.order + 1;
    at = OrderFound{next, trials.measure(next)};
  }
  return at;
}

OrderFound search_order(OrderTrials &trials, OrderFound start, double target, int min_order, int max_order)
{
  OrderFound at = raise_order(trials, start, target, max_order);
  // a lower order may meet the target too (calibrated errors are upper bounds for most point
  // sets): tried while the error is below half the target, taken if it meets the target and
  // differs from the current one (an equal error means the tree has no expansions the order
  // acts on, e.g. a direct sum over few leaves: the order says nothing there, it is kept)
  while (at.order <= start.order && at.order > min_order && at.error >= 0 && at.error <= 0.5 * target) {
    trials.keep();
    const OrderFound lower{at.order - 1, trials.measure(at.order - 1)};
    const bool same = std::fabs(lower.error - at.error) <= 1e-6 * at.error;
    if (lower.error >= 0 && lower.error <= target && !same) {
      at = lower;
      continue;
    }
    trials.restore();
    break;
  }
  return at;
}

}    // namespace kifmm
