// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// libFuzzer target: the clump template reader of fix clump/rigid, i.e. what the fix does with
// the pebbles of a molecule template (src/RIGID_CLUMP/clump_template.cpp: check_pebbles) and,
// for an accepted template, the union-of-spheres mass properties
// (src/RIGID_CLUMP/clump_union.cpp: union_mass_properties).
//
// Input: a molecule file as in potentials/ ("N atoms" header, Coords and Diameters sections;
// other sections are skipped). The file text is parsed here the way LAMMPS's molecule command
// reads those lines (whitespace tokens, numbers through strtod, which accepts "nan", "inf",
// hex floats and 1e308; a pebble not listed keeps coordinate 0 and diameter 0), because
// Debian's LAMMPS (no exceptions) cannot run in-process under a fuzzer: its errors end the
// process. At most 48 pebbles (the union integration of a large template takes seconds).
//
// Checks: no crash, no UB (ASan + UBSan), no hang (libFuzzer -timeout), and for every accepted
// template mass properties that are finite and possible:
//   max ball volume <= volume <= sum of ball volumes (within the integration accuracy),
//   centre of mass inside the bounding box of the balls, principal-moment-like inequalities
//   (diagonal inertia >= 0, Ixx + Iyy >= Izz and its permutations).
#include "clump_template.h"
#include "clump_union.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace {

bool number(const std::string &t, double &v)
{
  const char *s = t.c_str();
  char *end = nullptr;
  v = std::strtod(s, &end);
  return end != s && *end == '\0';
}

}    // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  std::string text(reinterpret_cast<const char *>(data), size);
  std::istringstream in(text);
  std::string line, section;
  long natoms = -1;
  std::vector<clump::Sphere> s;
  while (std::getline(in, line)) {
    auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string t; words >> t;) w.push_back(t);
    if (w.empty()) continue;
    if (natoms < 0) {
      // header: "N atoms"
      double n;
      if (w.size() == 2 && w[1] == "atoms" && number(w[0], n) && n >= 1 && n <= 48 &&
          n == std::floor(n)) {
        natoms = (long) n;
        s.assign(natoms, clump::Sphere{{0.0, 0.0, 0.0}, 0.0});
      }
      continue;
    }
    if (w.size() == 1 && std::isalpha((unsigned char) w[0][0])) {
      section = w[0];
      continue;
    }
    double id;
    if (!number(w[0], id) || id < 1 || id > natoms || id != std::floor(id)) continue;
    clump::Sphere &p = s[(long) id - 1];
    double v[3];
    if (section == "Coords" && w.size() >= 4 && number(w[1], v[0]) && number(w[2], v[1]) &&
        number(w[3], v[2]))
      for (int d = 0; d < 3; ++d) p.x[d] = v[d];
    else if (section == "Diameters" && w.size() >= 2 && number(w[1], v[0]))
      p.r = 0.5 * v[0];
  }
  if (natoms < 1) return 0;

  const std::string why = clump::check_pebbles(s);
  if (!why.empty()) return 0;    // fix clump/rigid stops with this message

  const double tol = 1e-3;
  clump::MassProperties m = clump::union_mass_properties(s, 1.0, tol);
  double vmax = 0.0, vsum = 0.0, lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (const auto &p : s) {
    const double v = 4.0 / 3.0 * M_PI * p.r * p.r * p.r;
    vmax = std::max(vmax, v);
    vsum += v;
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p.x[d] - p.r);
      hi[d] = std::max(hi[d], p.x[d] + p.r);
    }
  }
  if (!std::isfinite(m.volume) || !std::isfinite(m.mass) || !(m.volume > 0.0)) abort();
  const double slack = 20 * tol + 1e-9;
  if (m.volume > vsum * (1 + slack) || m.volume < vmax * (1 - slack)) abort();
  for (int d = 0; d < 3; ++d) {
    const double pad = slack * (hi[d] - lo[d]);
    if (!std::isfinite(m.com[d]) || m.com[d] < lo[d] - pad || m.com[d] > hi[d] + pad) abort();
  }
  const double *I = m.itensor;
  for (int k = 0; k < 6; ++k)
    if (!std::isfinite(I[k])) abort();
  const double scale = I[0] + I[1] + I[2];
  if (!(scale >= 0.0)) abort();
  for (int k = 0; k < 3; ++k)
    if (I[k] < -slack * scale) abort();
  if (I[0] + I[1] < I[2] - slack * scale || I[1] + I[2] < I[0] - slack * scale ||
      I[0] + I[2] < I[1] - slack * scale)
    abort();
  return 0;
}
