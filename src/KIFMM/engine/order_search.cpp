// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The order for a requested accuracy, measured on the points (kifmm.h: raise_order,
// search_order): the policy, with the caller's evaluations and error measurements.
#include "kifmm.h"

#include <cmath>

namespace kifmm {

namespace {
// the error of the lower of two orders: the difference over all points plus the higher order's
// error (triangle inequality); < 0 when either is unknown
double lower_order_bound(double difference, double higher_error)
{
  return difference >= 0 && higher_error >= 0 ? difference + higher_error : -1.0;
}

// whether the lower of two orders may meet the request: its error is at least their difference
// minus the higher order's error (the other side of the triangle)
bool may_meet(double difference, double higher_error, double request)
{
  return difference - higher_error <= request;
}

// the current evaluation (an order below `higher`) bounded again from an evaluation at the order
// above `higher` (the current one kept and returned to): that bound when it meets the request,
// else < 0 and `higher` evaluated again (its error into higher_error when given)
double bound_from_above(OrderTrials &trials, int higher, double request, double *higher_error)
{
  trials.keep();
  trials.step(OrderTrials::Step::bound);
  const double error = trials.measure(higher + 1);
  const double bound = lower_order_bound(trials.difference_from_kept(), error);
  trials.restore();
  if (bound >= 0 && bound <= request) return bound;
  trials.step(OrderTrials::Step::back);
  const double again = trials.measure(higher);
  if (higher_error) *higher_error = again;
  return -1.0;
}
}    // namespace

OrderFound raise_order(OrderTrials &trials, OrderFound at, double request, int max_order)
{
  const double target = order_search_margin * request;
  while (at.error > target && at.order < max_order) {
    trials.keep();
    trials.step(OrderTrials::Step::raise);
    OrderFound next{at.order + 1, trials.measure(at.order + 1)};
    // the sampled error of `at` may overestimate it: the bound over all points decides
    const double difference = trials.difference_from_kept();
    double bound = lower_order_bound(difference, next.error);
    if (bound >= 0 && bound <= request) {
      trials.restore();
      return OrderFound{at.order, bound};
    }
    if (bound >= 0 && may_meet(difference, next.error, request) && next.order < max_order) {
      // bounded again from the order above `next`, whose error is smaller; else `next` again
      trials.restore();
      bound = bound_from_above(trials, next.order, request, &next.error);
      if (bound >= 0) return OrderFound{at.order, bound};
    }
    at = next;
  }
  return at;
}

OrderFound search_order(OrderTrials &trials, OrderFound start, double request, int min_order, int max_order)
{
  const double target = order_search_margin * request;
  OrderFound at = raise_order(trials, start, request, max_order);
  // a lower order may meet the request too (calibrated errors are upper bounds for most point
  // sets): tried while the error is below half the target, taken if it meets the request and
  // differs from the current one (an equal error means the tree has no expansions the order
  // acts on, e.g. a direct sum over few leaves: the order says nothing there, it is kept)
  while (at.order <= start.order && at.order > min_order && at.error >= 0 && at.error <= 0.5 * target) {
    trials.keep();
    trials.step(OrderTrials::Step::lower);
    const OrderFound lower{at.order - 1, trials.measure(at.order - 1)};
    const bool same = std::fabs(lower.error - at.error) <= 1e-6 * at.error;
    const double difference = trials.difference_from_kept();
    double bound = lower_order_bound(difference, at.error);
    bool meets = bound >= 0 ? bound <= request : lower.error >= 0 && lower.error <= target;
    if (!meets && !same && bound >= 0 && may_meet(difference, at.error, request) && at.order < max_order) {
      // the bound misses the request, the other side of the triangle does not: bounded again
      // against the order above, whose error is smaller (else at.order evaluated again: the
      // kept evaluation is lower's)
      bound = bound_from_above(trials, at.order, request, nullptr);
      meets = bound >= 0;
      if (!meets) break;
    }
    if (meets && !same) {
      at = OrderFound{lower.order, bound >= 0 ? bound : lower.error};
      continue;
    }
    trials.restore();
    break;
  }
  return at;
}

}    // namespace kifmm
