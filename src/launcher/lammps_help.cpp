// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// lmp_kifmm's definition of LAMMPS::help(), the -h output.
//
// LAMMPS prints its help from inside its constructor and then ends the process, so lmp_kifmm
// cannot add the package's styles first; and LAMMPS 29 Sep 2021 lists the styles compiled into
// liblammps, not those of its style maps. liblammps calls help() through its PLT, so this
// definition in the executable (exported with -rdynamic) runs instead: it captures the text of
// liblammps's own help() and adds the package's styles and the `plugin` command to LAMMPS's
// lists, formatted as LAMMPS formats them. Test: unittest/plugin (launcher.help_lists_styles).
#include "package_styles.h"

#include "lammps.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dlfcn.h>
#include <map>
#include <sstream>
#include <string>
#include <vector>

using namespace LAMMPS_NS;

namespace {

// title of LAMMPS's help section that lists styles of this kind
const std::map<std::string, std::string> section_of = {
    {"pair", "Pair styles"},         {"bond", "Bond styles"},
    {"angle", "Angle styles"},       {"dihedral", "Dihedral styles"},
    {"improper", "Improper styles"}, {"kspace", "KSpace styles"},
    {"fix", "Fix styles"},           {"compute", "Compute styles"},
    {"region", "Region styles"},     {"command", "Command styles"}};

// LAMMPS's layout of a style list: names in columns of 16 (32, 48, ... for long ones), a new
// line before a name that would pass column 80; names starting upper case are internal
void append_name(std::string &line, std::vector<std::string> &out, const std::string &name)
{
  if (name.empty() || std::isupper((unsigned char) name[0])) return;
  const std::size_t len = name.size();
  if (line.size() + len > 80) {
    out.push_back(line);
    line.clear();
  }
  const std::size_t width = (len / 16 + 1) * 16;
  line += name + std::string(width - len, ' ');
}

// `help` with the names of `extra` (section title -> names) added to the end of each list
std::string with_styles(const std::string &help,
                        const std::map<std::string, std::vector<std::string>> &extra)
{
  std::vector<std::string> lines;
  std::istringstream in(help);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  const bool final_newline = !help.empty() && help.back() == '\n';
  std::vector<std::string> out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    out.push_back(lines[i]);
    if (lines[i].rfind("* ", 0) != 0) continue;
    std::string title = lines[i].substr(2);
    if (!title.empty() && title.back() == ':') title.pop_back();
    auto it = extra.find(title);
    if (it == extra.end()) continue;
    // the list: after one blank line, up to the next blank line
    std::size_t j = i + 1;
    if (j < lines.size() && lines[j].empty()) out.push_back(lines[j++]);
    std::string last;
    for (; j < lines.size() && !lines[j].empty(); ++j) {
      if (!last.empty()) out.push_back(last);
      last = lines[j];
    }
    for (const auto &name : it->second) append_name(last, out, name);
    if (!last.empty()) out.push_back(last);
    i = j - 1;
  }
  std::string text;
  for (std::size_t k = 0; k < out.size(); ++k) {
    text += out[k];
    if (k + 1 < out.size() || final_newline) text += '\n';
  }
  return text;
}

}    // namespace

void LAMMPS::help()
{
  // liblammps's LAMMPS::help(), the next definition after this executable's
  using Help = void (*)(LAMMPS *);
  auto lammps_help = reinterpret_cast<Help>(dlsym(RTLD_NEXT, "_ZN9LAMMPS_NS6LAMMPS4helpEv"));
  if (!lammps_help) {
    if (screen) fprintf(screen, "lmp_kifmm: LAMMPS's help text is not available (%s)\n", dlerror());
    return;
  }
  std::map<std::string, std::vector<std::string>> extra;
  for (const auto &s : kifmm_lammps::package_styles()) {
    auto it = section_of.find(s.style);
    if (it != section_of.end()) extra[it->second].push_back(s.name);
  }
  extra["Command styles"].push_back("plugin");

  char *buf = nullptr;
  std::size_t size = 0;
  FILE *mem = open_memstream(&buf, &size);
  if (!mem) {
    lammps_help(this);
    return;
  }
  FILE *out = screen;
  screen = mem;
  lammps_help(this);
  screen = out;
  fclose(mem);
  const std::string text = with_styles(std::string(buf, size), extra);
  free(buf);
  fputs(text.c_str(), out);
  fflush(out);
}
