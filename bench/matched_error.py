# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Shared by the LAMMPS-level benchmarks (bench/periodic_boxes, bench/dipoles): a solver's time
at a given error, log-log interpolated between its measured settings."""
import math


def time_at(err, points):
    """Time at error err from (error, time) pairs (None entries skipped); None outside their range."""
    pts = sorted((e, t) for e, t in points if e is not None and t is not None)
    for (e1, t1), (e2, t2) in zip(pts, pts[1:]):
        if e1 <= err <= e2:
            w = (math.log(err) - math.log(e1)) / (math.log(e2) - math.log(e1)) if e2 > e1 else 0
            return math.exp(math.log(t1) + w * (math.log(t2) - math.log(t1)))
    return None


def frontier(points):
    """The (error, time) pairs no other pair beats in both (None entries skipped): a solver tuned
    for speed at each error, from a sweep of its settings."""
    pts = sorted((e, t) for e, t in points if e is not None and t is not None)
    out = []
    for e, t in pts:
        if not out or t < out[-1][1]:
            out.append((e, t))
    return out
