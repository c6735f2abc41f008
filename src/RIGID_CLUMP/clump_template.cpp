// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "clump_template.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace clump {

std::string check_pebbles(const std::vector<Sphere> &s, const std::vector<long> &labels)
{
  auto name = [&](std::size_t i) { return i < labels.size() ? labels[i] : (long) i + 1; };
  std::ostringstream msg;
  if (s.empty()) return "no pebbles";
  double rmin = 0.0, rmax = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    for (int d = 0; d < 3; ++d)
      if (!std::isfinite(s[i].x[d])) {
        msg << "pebble " << name(i) << " has a non-finite coordinate (" << s[i].x[0] << ", "
            << s[i].x[1] << ", " << s[i].x[2] << ")";
        return msg.str();
      }
    if (!std::isfinite(s[i].r) || !(s[i].r > 0.0)) {
      msg << "pebble " << name(i) << " has diameter " << 2.0 * s[i].r
          << " (must be finite and > 0)";
      return msg.str();
    }
    // the moments of inertia grow as r^5: outside this range they overflow or underflow
    if (s[i].r < 1e-60 || s[i].r > 1e60) {
      msg << "pebble " << name(i) << " has diameter " << 2.0 * s[i].r
          << " (must be between 2e-60 and 2e60: its moments of inertia would not fit a double)";
      return msg.str();
    }
    rmin = i == 0 ? s[i].r : std::min(rmin, s[i].r);
    rmax = std::max(rmax, s[i].r);
  }
  if (rmax > max_radius_ratio * rmin) {
    msg << "pebble diameters from " << 2.0 * rmin << " to " << 2.0 * rmax
        << ": a ratio above " << max_radius_ratio << " is not supported";
    return msg.str();
  }
  for (std::size_t i = 1; i < s.size(); ++i) {
    double d2 = 0.0;
    for (int d = 0; d < 3; ++d) d2 += (s[i].x[d] - s[0].x[d]) * (s[i].x[d] - s[0].x[d]);
    // also catches an overflow of d2 to inf
    if (!(std::sqrt(d2) <= max_extent_in_radii * rmax)) {
      msg << "pebble " << name(i) << " is farther than " << max_extent_in_radii
          << " largest radii from pebble " << name(0) << " (not a clump)";
      return msg.str();
    }
  }
  // relative to pebble 0 (the cell list's integer cell indices stay in range)
  std::vector<Sphere> rel(s);
  for (auto &p : rel)
    for (int d = 0; d < 3; ++d) p.x[d] -= s[0].x[d];
  auto dups = duplicate_spheres(rel);
  if (!dups.empty()) {
    const auto &d = dups.front();
    msg << dups.size() << " pair(s) of duplicate (coincident) pebbles, first: pebbles "
        << name(d[0]) << " and " << name(d[1]) << " at (" << s[d[0]].x[0] << ", "
        << s[d[0]].x[1] << ", " << s[d[0]].x[2] << ")";
    return msg.str();
  }
  return "";
}

}    // namespace clump
