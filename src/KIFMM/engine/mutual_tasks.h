// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Task schedule of a mutual near field (p2p_mutual.h): each node (leaf or grid cell) with
// itself, then the pairs of adjacent nodes, one OpenMP task each, with a dependence on each
// of its nodes: tasks that share a node run in creation order (a fixed order per target, so
// results do not depend on the threads), all others as soon as a thread is free (no barrier
// per color: on a loaded machine one descheduled thread would stall every round).
#pragma once

#include "interaction_lists.h"

#include <cstddef>
#include <vector>

namespace kifmm {

// run(a, b, shift, self_pair, index) evaluates one pair (shift: the root shift of b; index: of
// the pair in `pairs`, or of the node in `self`) and returns its coincident pairs; the sum is
// returned.
template <class Run>
std::size_t run_mutual_tasks(std::size_t nnodes, const std::vector<int> &self, const std::vector<MutualPair> &pairs,
                             Run run)
{
  const int ns = (int) self.size(), np = (int) pairs.size();
  std::vector<std::size_t> z(ns + np, 0);
  std::vector<char> dep(nnodes);
  char *d = dep.data();
  std::size_t *zp = z.data();
  const signed char no_shift[3] = {0, 0, 0};
  // The tasks are created inside an explicit parent task, not by the implicit task of the
  // `single`: libgomp (GCC 12) never frees the dependence table of an implicit task of a pooled
  // thread, which leaked ~8 kB per evaluation whenever a non-master thread ran the `single`
  // (measured with LeakSanitizer: 29 blocks after 400 evaluations); an explicit task's table is
  // freed when it ends.
#pragma omp parallel
#pragma omp single
#pragma omp task
  {
    for (int i = 0; i < ns; ++i) {
#pragma omp task depend(inout : d[self[i]]) firstprivate(i)
      zp[i] = run(self[i], self[i], no_shift, true, i);
    }
    for (int e = 0; e < np; ++e) {
      const int a = pairs[e].a, b = pairs[e].b;
#pragma omp task depend(inout : d[a], d[b]) firstprivate(e)
      zp[ns + e] = run(pairs[e].a, pairs[e].b, pairs[e].shift, false, e);
    }
#pragma omp taskwait
  }
  std::size_t zeros = 0;
  for (std::size_t v : z) zeros += v;
  return zeros;
}

}    // namespace kifmm
