// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Creating, clearing and re-creating LAMMPS instances with kifmm running, and loading and
// unloading plugins, 100 times in one process: resident memory must stay flat.
#include "lammps_fixture.h"
#include "package_styles.h"
#include "plugin_registry.h"

#include "lammps.h"

#include <fstream>
#include <string>

using kifmm_test::LammpsFixture;

namespace {

double resident_mb()
{
  std::ifstream in("/proc/self/status");
  std::string key;
  while (in >> key) {
    if (key == "VmRSS:") {
      double kb;
      in >> kb;
      return kb / 1024.0;
    }
    std::getline(in, key);
  }
  return -1;
}

class Lifecycle : public LammpsFixture {
 protected:
  void cycle()
  {
    create();
    kifmm_lammps::plugin_load(lmp, KIFMM_PLUGIN_PATH);
    kifmm_lammps::plugin_load(lmp, TEST_PLUGIN_PATH);
    commands(R"(
      units lj
      atom_style charge
      boundary f f f
      region box block 0 1 0 1 0 1
      create_box 1 box
      create_atoms 1 random 500 4711 box
      mass 1 1.0
      set group all charge 1.0
      pair_style zero 0.01
      pair_coeff * *
      kspace_style kifmm 1e-4
      fix count all kifmm/test/count
      run 2 post no
      clear
    )");
    kifmm_lammps::add_package_styles(lmp);
    kifmm_lammps::plugin_restore(lmp);
    command("kifmm_test_hello 1");
    kifmm_lammps::plugin_clear(lmp);
    destroy();
  }
};

TEST_F(Lifecycle, HundredCyclesLeakNothing)
{
  for (int i = 0; i < 10; ++i) cycle();    // warm-up: caches, allocator pools
  const double before = resident_mb();
  for (int i = 0; i < 90; ++i) cycle();
  const double after = resident_mb();
  printf("  resident memory after 10 cycles %.1f MB, after 100 cycles %.1f MB\n", before, after);
  EXPECT_LT(after - before, 3.0) << "resident memory grew over 90 create/clear/load cycles";
  create();    // the fixture's TearDown expects an instance
}

}    // namespace
