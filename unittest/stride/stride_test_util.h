// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Shared input of the fix kifmm/stride tests: a small cube of +-1 charges (edge^3 atoms, default 125, in rock-salt
// order on a slightly disordered simple cubic lattice, unit spacing, net charge +1 for odd edge) in a fixed open box.
#pragma once

#include <string>

namespace stride_test {

// `pair` is the pair style line(s); the caller adds fixes and runs.
// `edge` atoms per edge (at most 10; 10: 1000 atoms, several octree leaves).
inline std::string charged_cube(const std::string &pair = "pair_style zero 1.0\npair_coeff * *",
                                const std::string &velocity = "velocity all create 0.5 777 loop geom",
                                int edge = 5)
{
  const std::string hi = std::to_string(edge - 0.5);
  return "units lj\n"
         "atom_style charge\n"
         "boundary f f f\n"
         "atom_modify map array\n"
         "region box block -6 10 -6 10 -6 10 units box\n"
         "create_box 2 box\n"
         "lattice sc 1.0\n"
         "region inner block -0.5 " + hi + " -0.5 " + hi + " -0.5 " + hi + " units box\n"
         "create_atoms 1 region inner\n"
         "displace_atoms all random 0.1 0.1 0.1 4711 units box\n"
         "mass * 1.0\n"
         "variable q atom 2*(id%2)-1\n"    // rock salt order: x+y+z parity
         "set group all charge v_q\n" +
      velocity + "\n" + pair +
      "\n"
      "kspace_style kifmm 1e-6\n"
      "kspace_modify kifmm tune no\n"    // runs are compared bit for bit: the modelled tree, not a timed one
      "fix nve all nve\n"
      "timestep 0.002\n"
      "thermo_style custom step pe ke etotal elong\n"
      "thermo_modify norm no\n";
}

}    // namespace stride_test
