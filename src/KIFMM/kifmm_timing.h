// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Time spent by kspace_style kifmm during a run, by phase, and its end-of-run table
// (min/avg/max over ranks, like LAMMPS's own timing breakdown). The table is printed by an
// internal fix (ID KIFMM_TIMING) that the kspace style creates, because fixes are what LAMMPS
// calls at the end of a run.
#pragma once

#include "fix.h"

#include <cstddef>

namespace kifmm {
struct Stats;
}

namespace LAMMPS_NS {

struct KIFMMTiming {
  // Polarize: the solve for induced dipoles (fix kifmm/polarize) before the evaluation, all its
  // field evaluations included
  enum Phase { Tree, Lists, Upward, M2L, WX, Downward, P2P, Comm, Polarize, Other, NPHASES };
  double t[NPHASES] = {};
  long evaluations = 0;
  double points = 0;    // sum over evaluations of this rank's targets
  double bytes = 0;     // sum over evaluations of the bytes this rank sent (communication volume)

  void reset() { *this = KIFMMTiming(); }
  // adds one evaluation: engine phases from its stats, comm time and bytes sent, the time of
  // the solve for induced dipoles, total
  void add(const kifmm::Stats &s, double comm, double total, std::size_t targets, std::size_t bytes_sent = 0,
           double polarize = 0);
};

class FixKIFMMTiming : public Fix {
 public:
  FixKIFMMTiming(class LAMMPS *, int, char **);
  int setmask() override { return 0; }
  void post_run() override;
};

// prints the table of `timing` (collective over ranks)
void print_kifmm_timing(class LAMMPS *lmp, const KIFMMTiming &timing);

}    // namespace LAMMPS_NS
