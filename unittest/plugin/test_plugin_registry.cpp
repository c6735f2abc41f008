// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// In-process tests of the plugin registry behind lmp_kifmm's `plugin` command, of the fmt
// compatibility (formatted LAMMPS messages from a plugin style) and of the package table.
#include "lammps_fixture.h"
#include "package_styles.h"
#include "plugin_registry.h"

#include "force.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"

using kifmm_test::LammpsFixture;

namespace {

const std::string plugin_path = TEST_PLUGIN_PATH;

class PluginRegistry : public LammpsFixture {
 protected:
  void TearDown() override
  {
    kifmm_lammps::plugin_clear(lmp);
    LammpsFixture::TearDown();
  }
  bool has_command(const std::string &name)
  {
    return lmp->input->command_map->count(name) > 0;
  }
  bool has_fix(const std::string &name) { return lmp->modify->fix_map->count(name) > 0; }
};

TEST_F(PluginRegistry, LoadRegistersStylesAndUnloadRemovesThem)
{
  EXPECT_FALSE(has_command("kifmm_test_hello"));
  kifmm_lammps::plugin_load(lmp, plugin_path);
  EXPECT_EQ(kifmm_lammps::plugin_count(), 2);
  EXPECT_TRUE(has_command("kifmm_test_hello"));
  EXPECT_TRUE(has_fix("kifmm/test/count"));
  command("kifmm_test_hello 3");

  kifmm_lammps::plugin_unload(lmp, "command", "kifmm_test_hello");
  EXPECT_FALSE(has_command("kifmm_test_hello"));
  EXPECT_TRUE(has_fix("kifmm/test/count"));
  EXPECT_EQ(kifmm_lammps::plugin_count(), 1);
}

TEST_F(PluginRegistry, PluginFixRunsAndIsDeletedOnUnload)
{
  kifmm_lammps::plugin_load(lmp, plugin_path);
  commands(R"(
    region box block 0 2 0 2 0 2
    create_box 1 box
    create_atoms 1 single 1 1 1
    mass 1 1.0
    fix counter all kifmm/test/count
    run 7
  )");
  EXPECT_DOUBLE_EQ(evaluate("f_counter"), 7.0);
  kifmm_lammps::plugin_unload(lmp, "fix", "kifmm/test/count");
  EXPECT_LT(lmp->modify->find_fix("counter"), 0) << "fix instance must be deleted on unload";
}

TEST_F(PluginRegistry, ReloadingIsIdempotent)
{
  kifmm_lammps::plugin_load(lmp, plugin_path);
  kifmm_lammps::plugin_load(lmp, plugin_path);
  EXPECT_EQ(kifmm_lammps::plugin_count(), 2);
  kifmm_lammps::plugin_clear(lmp);
  EXPECT_EQ(kifmm_lammps::plugin_count(), 0);
  EXPECT_FALSE(has_command("kifmm_test_hello"));
}

TEST_F(PluginRegistry, RestorePutsStylesIntoANewInstance)
{
  kifmm_lammps::plugin_load(lmp, plugin_path);
  create();    // a new instance knows nothing of the plugin until restored
  EXPECT_FALSE(has_command("kifmm_test_hello"));
  kifmm_lammps::plugin_restore(lmp);
  EXPECT_TRUE(has_command("kifmm_test_hello"));
}

TEST_F(PluginRegistry, MissingFileIsReportedNotFatal)
{
  kifmm_lammps::plugin_load(lmp, "/nonexistent/plugin.so");
  EXPECT_EQ(kifmm_lammps::plugin_count(), 0);
}

TEST_F(PluginRegistry, FormattedErrorFromPluginStyle)
{
  kifmm_lammps::plugin_load(lmp, plugin_path);
  EXPECT_LAMMPS_ERROR(command("kifmm_test_hello -3"),
                      "ERROR: kifmm_test_hello: count must be >= 0, got -3");
}

TEST_F(PluginRegistry, FormattedLogMessage)
{
  kifmm_lammps::plugin_load(lmp, plugin_path);
  const std::string text = captured("kifmm_test_hello 42");
  EXPECT_NE(text.find("kifmm_test_hello: hello 42 times"), std::string::npos) << text;
}

TEST_F(PluginRegistry, BadArgumentsToThePluginCommandGiveClearErrors)
{
  kifmm_lammps::install_launcher_styles(lmp);
  ASSERT_TRUE(has_command("plugin"));
  EXPECT_LAMMPS_ERROR(command("plugin"), "ERROR: Illegal plugin command: expected load, unload, list");
  EXPECT_LAMMPS_ERROR(command("plugin lod x.so"), "ERROR: Illegal plugin command: unknown keyword lod");
  EXPECT_LAMMPS_ERROR(command("plugin load"), "ERROR: Illegal plugin load command: missing file name");
  EXPECT_LAMMPS_ERROR(command("plugin unload fix"), "ERROR: Illegal plugin unload command: expected");
  EXPECT_LAMMPS_ERROR(command("plugin list all"), "ERROR: Illegal plugin list command: unexpected argument all");
  EXPECT_LAMMPS_ERROR(command("plugin clear now"), "ERROR: Illegal plugin clear command: unexpected argument now");
  EXPECT_LAMMPS_ERROR(command("plugin restore 1"),
                      "ERROR: Illegal plugin restore command: unexpected argument 1");
}

TEST_F(PluginRegistry, UnknownStyleGivesLammpsOwnError)
{
  EXPECT_LAMMPS_ERROR(command("kspace_style no_such_kspace"), "Unrecognized kspace style");
}

TEST(PackageStyles, EveryEntryIsComplete)
{
  for (const auto &s : kifmm_lammps::package_styles()) {
    EXPECT_NE(s.style, nullptr);
    EXPECT_NE(s.name, nullptr);
    EXPECT_NE(s.creator.v1, nullptr) << s.name;
    EXPECT_STREQ(s.version, kifmm_lammps::lammps_version_built_against);
  }
}

}    // namespace
