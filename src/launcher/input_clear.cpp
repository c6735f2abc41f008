// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// lmp_kifmm's definition of LAMMPS's `clear` command.
//
// `clear` destroys and recreates Force, Modify, Domain, ... and with them the style maps, so
// the package's built-in styles and the styles of loaded plugins would be gone afterwards.
// liblammps calls Input::clear() through its PLT, so this definition in the executable
// (exported with -rdynamic) takes its place: it does what LAMMPS's clear does and then puts the
// styles back, as plugin-enabled LAMMPS releases do. Test: unittest/launcher (clear_keeps_styles).
#include "plugin_registry.h"

#include "error.h"
#include "input.h"
#include "lammps.h"

using namespace LAMMPS_NS;

void Input::clear()
{
  if (narg > 0) error->all(FLERR, "Illegal clear command: unexpected argument {}", arg[0]);
  lmp->destroy();
  lmp->create();
  lmp->post_create();
  kifmm_lammps::install_launcher_styles(lmp);
}
