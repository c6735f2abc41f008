// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The per-process registry of styles loaded from plugin shared objects, behind lmp_kifmm's
// `plugin load|unload|list|clear|restore` command. As in LAMMPS, plugins are a property of
// the executable: they stay loaded across `clear` and are restored into the new style maps.
#pragma once

#include <string>

namespace LAMMPS_NS {
class LAMMPS;
}

namespace kifmm_lammps {

void plugin_load(LAMMPS_NS::LAMMPS *lmp, const std::string &file);
void plugin_unload(LAMMPS_NS::LAMMPS *lmp, const std::string &kind, const std::string &name);
void plugin_clear(LAMMPS_NS::LAMMPS *lmp);
void plugin_list(LAMMPS_NS::LAMMPS *lmp);
// Puts every style of every loaded plugin into the maps of `lmp` (after `clear`).
void plugin_restore(LAMMPS_NS::LAMMPS *lmp);
int plugin_count();

// Built-in package styles, the `plugin` command and all loaded plugins: what a fresh or
// cleared LAMMPS instance of lmp_kifmm must have.
void install_launcher_styles(LAMMPS_NS::LAMMPS *lmp);

}    // namespace kifmm_lammps
