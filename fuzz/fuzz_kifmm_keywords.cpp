// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// libFuzzer target: the parser of `kspace_style kifmm ACCURACY` and `kspace_modify kifmm ...`.
// Input: whitespace-separated tokens; the first is the accuracy, the rest follow "kifmm".
// Checks: no crash/UB (ASan+UBSan), and every accepted input leaves settings in range.
#include "kifmm_keywords.h"

#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

using namespace kifmm_lammps;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  std::string text(reinterpret_cast<const char *>(data), size);
  std::istringstream in(text);
  std::vector<std::string> tokens;
  for (std::string t; in >> t;) tokens.push_back(t);
  if (tokens.empty()) return 0;

  KIFMMSettings s;
  if (parse_accuracy(tokens[0], s).empty() && !(s.accuracy > 0 && s.accuracy < 1)) abort();

  std::vector<std::string> args = {"kifmm"};
  args.insert(args.end(), tokens.begin() + 1, tokens.end());
  int consumed = -1;
  std::string why = parse_kifmm_keywords(args, s, consumed);
  if (why.empty()) {
    if (consumed < 2 || consumed > (int) args.size()) abort();
    if (s.order != 0 && (s.order < kifmm_min_order || s.order > kifmm_max_order)) abort();
    if (s.grid < -1 || (s.grid > 0 && (s.grid < kifmm_min_grid || s.grid > kifmm_max_grid))) abort();
    if (s.leaf < 0 || s.gravity_G <= 0 || s.kappa < 0 || s.check_every < 0) abort();
  } else if (consumed != 0) {
    abort();
  }
  return 0;
}
