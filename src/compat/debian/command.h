// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Base class of LAMMPS input-script commands (CommandStyle). Debian's liblammps-dev does not
// ship command.h; this declares the identical interface of LAMMPS 29Sep2021 (a Pointers-based
// class with one pure virtual `command`), which is all a command style needs.
#pragma once

#include "pointers.h"

namespace LAMMPS_NS {

class Command : protected Pointers {
 public:
  Command(class LAMMPS *lmp) : Pointers(lmp) {}
  virtual void command(int narg, char **arg) = 0;
};

}    // namespace LAMMPS_NS
