// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Checks of the pebbles of a clump (a molecule template's Coords and Diameters, or the pebbles
// of one clump of atoms) before the union mass properties are integrated. No LAMMPS
// dependency: fix clump/rigid calls it, and the libFuzzer target fuzz/fuzz_clump_template.cpp
// drives it (with the union integration) on arbitrary template files.
//
// LAMMPS's molecule reader accepts any number strtod() accepts ("nan", "inf", "1e308"), so the
// checks cover what the integration cannot handle:
//   - no pebbles;
//   - a non-finite coordinate or diameter, a diameter <= 0;
//   - a scale the integration and the duplicate search cannot resolve: largest/smallest radius
//     above 1e6, or a pebble farther than 1e9 largest radii from the first pebble;
//   - duplicate (coincident) pebbles.
#pragma once

#include "clump_union.h"

#include <string>
#include <vector>

namespace clump {

constexpr double max_radius_ratio = 1e6;
constexpr double max_extent_in_radii = 1e9;

// "" if the pebbles can be a clump, else the problem; labels[i] names pebble i in the message
// (1-based template index or atom ID; i + 1 if labels is empty).
std::string check_pebbles(const std::vector<Sphere> &s, const std::vector<long> &labels = {});

}    // namespace clump
