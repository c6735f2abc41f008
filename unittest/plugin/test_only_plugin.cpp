// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// A LAMMPS plugin built only for the tests (kifmm_test_plugin.so). It provides two small,
// honest styles that exercise the plugin ABI and the fmt-formatted LAMMPS calls:
//   command kifmm_test_hello N   : logs "kifmm_test_hello: hello N times" (N >= 0), or fails
//                                  with a formatted error naming the bad value
//   fix ID group kifmm/test/count : counts the steps it was called at end_of_step
#include "command.h"
#include "lammpsplugin.h"

#include "error.h"
#include "fix.h"
#include "lammps.h"
#include "utils.h"

using namespace LAMMPS_NS;

namespace {

class TestHello : public Command {
 public:
  TestHello(LAMMPS *lmp) : Command(lmp) {}
  void command(int narg, char **arg) override
  {
    if (narg != 1) error->all(FLERR, "Illegal kifmm_test_hello command: expected 1 argument, got {}", narg);
    int n = utils::inumeric(FLERR, arg[0], false, lmp);
    if (n < 0) error->all(FLERR, "kifmm_test_hello: count must be >= 0, got {}", n);
    utils::logmesg(lmp, "kifmm_test_hello: hello {} times\n", n);
  }
};

class FixTestCount : public Fix {
 public:
  FixTestCount(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg)
  {
    if (narg != 3) error->all(FLERR, "Illegal fix kifmm/test/count command: unexpected argument {}", arg[3]);
    global_freq = 1;
    scalar_flag = 1;
    extscalar = 0;
  }
  int setmask() override { return FixConst::END_OF_STEP; }
  void end_of_step() override { ++count; }
  double compute_scalar() override { return count; }

 private:
  int count = 0;
};

void *make_hello(void *lmp)
{
  return new TestHello((LAMMPS *) lmp);
}
void *make_count(void *lmp, int narg, char **arg)
{
  return new FixTestCount((LAMMPS *) lmp, narg, arg);
}

}    // namespace

extern "C" void lammpsplugin_init(void *lmp, void *handle, void *regfunc)
{
  auto reg = (lammpsplugin_regfunc) regfunc;
  lammpsplugin_t plugin;
  plugin.version = ((LAMMPS *) lmp)->version;
  plugin.style = "command";
  plugin.name = "kifmm_test_hello";
  plugin.info = "test-only command";
  plugin.author = "lammps-kifmm tests";
  plugin.creator.v1 = &make_hello;
  plugin.handle = handle;
  reg(&plugin, lmp);

  plugin.style = "fix";
  plugin.name = "kifmm/test/count";
  plugin.info = "test-only fix";
  plugin.creator.v2 = &make_count;
  reg(&plugin, lmp);
}
