// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "plugin_registry.h"

#include "command.h"
#include "lammpsplugin.h"
#include "package_styles.h"
#include "style_maps.h"

#include "comm.h"
#include "error.h"
#include "input.h"
#include "lammps.h"
#include "utils.h"

#include <cstring>
#include <dlfcn.h>
#include <list>
#include <map>

using namespace LAMMPS_NS;

namespace kifmm_lammps {

namespace {

// A style loaded from a plugin; strings are copied because plugins often fill the
// lammpsplugin_t on the stack of their init function.
struct LoadedStyle {
  std::string version, kind, name, info, author;
  lammpsplugin_t entry;    // creator and handle; string pointers refer to the fields above
};

std::list<LoadedStyle> &loaded_styles()
{
  static std::list<LoadedStyle> styles;
  return styles;
}

std::map<void *, int> &dso_references()
{
  static std::map<void *, int> refs;
  return refs;
}

lammpsplugin_t as_entry(const LoadedStyle &s)
{
  lammpsplugin_t e = s.entry;
  e.version = s.version.c_str();
  e.style = s.kind.c_str();
  e.name = s.name.c_str();
  e.info = s.info.c_str();
  e.author = s.author.c_str();
  return e;
}

// lammpsplugin_regfunc handed to a plugin's lammpsplugin_init
void register_from_plugin(lammpsplugin_t *p, void *ptr)
{
  auto *lmp = static_cast<LAMMPS *>(ptr);
  const int me = lmp->comm->me;
  if (!is_known_style_kind(p->style)) {
    if (me == 0)
      lmp->error->warning(FLERR, "Ignoring plugin style {} of unsupported kind {}", p->name,
                          p->style);
    return;
  }
  if (p->version && strcmp(p->version, lmp->version) != 0 && me == 0)
    lmp->error->warning(FLERR, "Plugin {} was compiled for LAMMPS version {} not {}", p->name,
                        p->version, lmp->version);

  auto &styles = loaded_styles();
  for (auto it = styles.begin(); it != styles.end(); ++it)
    if (it->kind == p->style && it->name == p->name) {
      dso_references()[it->entry.handle]--;
      styles.erase(it);
      break;
    }
  LoadedStyle s{p->version ? p->version : "", p->style, p->name, p->info ? p->info : "",
                p->author ? p->author : "", *p};
  styles.push_back(s);
  dso_references()[p->handle]++;
  add_style_to_maps(lmp, as_entry(styles.back()), true);
}

void release_dso(void *handle)
{
  auto &refs = dso_references();
  auto it = refs.find(handle);
  if (it == refs.end()) return;
  if (--it->second <= 0) {
    refs.erase(it);
    if (handle) dlclose(handle);
  }
}

class PluginCommand : public Command {
 public:
  PluginCommand(LAMMPS *lmp) : Command(lmp) {}
  void command(int narg, char **arg) override
  {
    if (narg < 1) error->all(FLERR, "Illegal plugin command: expected load, unload, list, clear or restore");
    const std::string cmd = arg[0];
    if (cmd == "load") {
      if (narg < 2) error->all(FLERR, "Illegal plugin load command: missing file name");
      for (int i = 1; i < narg; ++i) plugin_load(lmp, arg[i]);
    } else if (cmd == "unload") {
      if (narg != 3) error->all(FLERR, "Illegal plugin unload command: expected 'plugin unload STYLE NAME'");
      plugin_unload(lmp, arg[1], arg[2]);
    } else if (cmd == "list") {
      if (narg != 1) error->all(FLERR, "Illegal plugin list command: unexpected argument {}", arg[1]);
      plugin_list(lmp);
    } else if (cmd == "clear") {
      if (narg != 1) error->all(FLERR, "Illegal plugin clear command: unexpected argument {}", arg[1]);
      plugin_clear(lmp);
    } else if (cmd == "restore") {
      if (narg != 1) error->all(FLERR, "Illegal plugin restore command: unexpected argument {}", arg[1]);
      plugin_restore(lmp);
    } else
      error->all(FLERR, "Illegal plugin command: unknown keyword {}", cmd);
  }
};

Command *make_plugin_command(LAMMPS *lmp)
{
  return new PluginCommand(lmp);
}

}    // namespace

void plugin_load(LAMMPS *lmp, const std::string &file)
{
  const int me = lmp->comm->me;
  dlerror();
  void *dso = dlopen(file.c_str(), RTLD_NOW | RTLD_GLOBAL);
  if (!dso) {
    if (me == 0) utils::logmesg(lmp, "Open of file {} failed: {}\n", file, dlerror());
    return;
  }
  dlerror();
  void *init = dlsym(dso, "lammpsplugin_init");
  if (!init) {
    const char *why = dlerror();
    dlclose(dso);
    if (me == 0)
      utils::logmesg(lmp, "Plugin symbol lookup failure in file {}: {}\n", file,
                     why ? why : "lammpsplugin_init not found");
    return;
  }
  if (me == 0) utils::logmesg(lmp, "Loading plugin(s) from {}\n", file);
  // dlopen of an already open object returns the same handle with a new reference: drop it
  // so that each file holds one dlopen reference, owned through its styles' counts
  const bool already_open = dso_references().count(dso) > 0;
  ((lammpsplugin_initfunc) init)(lmp, dso, (void *) &register_from_plugin);
  if (already_open)
    dlclose(dso);
  else if (dso_references().count(dso) == 0)
    dlclose(dso);    // plugin registered nothing
}

void plugin_unload(LAMMPS *lmp, const std::string &kind, const std::string &name)
{
  const int me = lmp->comm->me;
  if (!is_known_style_kind(kind)) {
    if (me == 0)
      lmp->error->warning(FLERR, "Ignoring unload: {} is not a supported plugin style", kind);
    return;
  }
  auto &styles = loaded_styles();
  for (auto it = styles.begin(); it != styles.end(); ++it) {
    if (it->kind == kind && it->name == name) {
      void *handle = it->entry.handle;
      styles.erase(it);
      remove_style_from_maps(lmp, kind, name);
      if (me == 0) utils::logmesg(lmp, "Unloading {} style {}\n", kind, name);
      // a built-in style of the same name comes back once the plugin's version is gone
      for (const auto &builtin : package_styles())
        if (kind == builtin.style && name == builtin.name) add_style_to_maps(lmp, builtin, false);
      release_dso(handle);
      return;
    }
  }
  if (me == 0)
    lmp->error->warning(FLERR, "Ignoring unload of {} style {}: not loaded from a plugin", kind,
                        name);
}

void plugin_clear(LAMMPS *lmp)
{
  while (!loaded_styles().empty()) {
    const std::string kind = loaded_styles().front().kind;    // copies: unload erases the entry
    const std::string name = loaded_styles().front().name;
    plugin_unload(lmp, kind, name);
  }
}

void plugin_list(LAMMPS *lmp)
{
  if (lmp->comm->me != 0) return;
  utils::logmesg(lmp, "Currently loaded plugins\n");
  int i = 0;
  for (const auto &s : loaded_styles())
    utils::logmesg(lmp, "{:4}: {} style plugin {}\n", ++i, s.kind, s.name);
}

void plugin_restore(LAMMPS *lmp)
{
  for (const auto &s : loaded_styles()) add_style_to_maps(lmp, as_entry(s), false);
}

int plugin_count()
{
  return (int) loaded_styles().size();
}

void install_launcher_styles(LAMMPS *lmp)
{
  add_package_styles(lmp);
  (*lmp->input->command_map)["plugin"] = &make_plugin_command;
  plugin_restore(lmp);
}

}    // namespace kifmm_lammps
