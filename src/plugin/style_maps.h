// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Putting a style (in LAMMPS plugin form) into, and taking it out of, the style maps of a
// LAMMPS instance (Force, Modify, Domain, Input). Used by lmp_kifmm for its built-in styles
// and for the `plugin` command, and by kifmmplugin.so's Python entry point.
#pragma once

#include "lammpsplugin.h"

#include <string>

namespace LAMMPS_NS {
class LAMMPS;
}

namespace kifmm_lammps {

// Adds the style to the matching map; returns false (and warns) for an unknown style kind.
// With `warn_override`, replacing an existing style of that name prints a LAMMPS warning.
bool add_style_to_maps(LAMMPS_NS::LAMMPS *lmp, const lammpsplugin_t &style, bool warn_override);

// Removes the style from its map and deletes instances of it that are in use (as LAMMPS's
// `plugin unload` does). Returns false if the style kind is unknown.
bool remove_style_from_maps(LAMMPS_NS::LAMMPS *lmp, const std::string &kind,
                            const std::string &name);

// The style kinds a plugin may provide.
bool is_known_style_kind(const std::string &kind);

}    // namespace kifmm_lammps
