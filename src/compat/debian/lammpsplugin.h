// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The LAMMPS plugin ABI (C linkage), as used by LAMMPS releases from 2022 on, where kspace
// styles are registrable too. Debian's liblammps-dev does not ship lammpsplugin.h; this is
// our declaration of the same binary interface so that kifmmplugin.so loads into any
// plugin-enabled LAMMPS and into lmp_kifmm.
#pragma once

extern "C" {

// creator of a style that takes only the LAMMPS instance (pair, kspace, command, ...)
typedef void *(lammpsplugin_factory1)(void *lmp);
// creator of a style that takes the command arguments (fix, compute, region)
typedef void *(lammpsplugin_factory2)(void *lmp, int narg, char **arg);

typedef struct {
  const char *version;    // LAMMPS version string the plugin was built against
  const char *style;      // "pair", "kspace", "fix", "compute", "command", ...
  const char *name;       // style name as typed in an input script
  const char *info;       // one-line description
  const char *author;
  union {
    lammpsplugin_factory1 *v1;
    lammpsplugin_factory2 *v2;
  } creator;
  void *handle;    // dlopen handle of the shared object that provides the style
} lammpsplugin_t;

typedef void (*lammpsplugin_regfunc)(lammpsplugin_t *plugin, void *lmp);
typedef void (*lammpsplugin_initfunc)(void *lmp, void *handle, void *regfunc);

// every plugin shared object exports this
void lammpsplugin_init(void *lmp, void *handle, void *regfunc);
}
