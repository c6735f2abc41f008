// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "kifmm_keywords.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace kifmm_lammps {

namespace {
bool to_double(const std::string &s, double &x)
{
  if (s.empty()) return false;
  char *end = nullptr;
  errno = 0;
  x = std::strtod(s.c_str(), &end);
  return errno == 0 && end && *end == '\0' && std::isfinite(x);
}

bool to_int(const std::string &s, int &n)
{
  if (s.empty()) return false;
  char *end = nullptr;
  errno = 0;
  long v = std::strtol(s.c_str(), &end, 10);
  if (errno != 0 || !end || *end != '\0' || v < -2147483647L || v > 2147483647L) return false;
  n = (int) v;
  return true;
}

// keyword yes|no at args[i]: "" or the error text (who: the command's prefix)
std::string yes_no(const std::vector<std::string> &args, std::size_t i, const std::string &who, bool &value)
{
  const std::string &kw = args[i];
  if (i + 1 >= args.size()) return who + "keyword '" + kw + "' needs a value: yes or no";
  if (args[i + 1] != "yes" && args[i + 1] != "no") return who + kw + " '" + args[i + 1] + "' must be yes or no";
  value = args[i + 1] == "yes";
  return "";
}
}    // namespace

const char *kernel_name(LongRangeKernel kernel)
{
  switch (kernel) {
    case LongRangeKernel::Coulomb:
      return "coulomb";
    case LongRangeKernel::Gravity:
      return "gravity";
    case LongRangeKernel::Yukawa:
      return "yukawa";
  }
  return "?";
}

std::string parse_accuracy(const std::string &token, KIFMMSettings &s)
{
  double a;
  if (!to_double(token, a))
    return "kspace_style kifmm: accuracy '" + token + "' is not a number";
  if (!(a > 0.0 && a < 1.0))
    return "kspace_style kifmm: accuracy " + token +
        " is out of range: it is a relative force error, 0 < accuracy < 1";
  s.accuracy = a;
  return "";
}

std::string parse_kifmm_keywords(const std::vector<std::string> &args, KIFMMSettings &s,
                                 int &consumed)
{
  consumed = 0;
  if (args.empty() || args[0] != "kifmm") return "kspace_modify: expected keyword 'kifmm'";
  const std::string who = "kspace_modify kifmm: ";
  size_t i = 1;
  if (args.size() == 1) return who + "no keyword given (kernel, order, leaf, grid, tune, check, jeans or cache)";
  while (i < args.size()) {
    const std::string &kw = args[i];
    if (kw == "kernel") {
      if (i + 1 >= args.size()) return who + "keyword 'kernel' needs a value: coulomb, gravity G or yukawa KAPPA";
      const std::string &k = args[i + 1];
      if (k == "coulomb") {
        s.kernel = LongRangeKernel::Coulomb;
        i += 2;
      } else if (k == "gravity" || k == "yukawa") {
        if (i + 2 >= args.size())
          return who + "kernel " + k + " needs a value (" + (k == "gravity" ? "G" : "KAPPA") + ")";
        double v;
        if (!to_double(args[i + 2], v))
          return who + "kernel " + k + ": '" + args[i + 2] + "' is not a number";
        if (k == "gravity") {
          if (!(v > 0)) return who + "kernel gravity: G must be > 0, got " + args[i + 2];
          s.kernel = LongRangeKernel::Gravity;
          s.gravity_G = v;
        } else {
          if (!(v > 0)) return who + "kernel yukawa: KAPPA must be > 0, got " + args[i + 2];
          s.kernel = LongRangeKernel::Yukawa;
          s.kappa = v;
        }
        i += 3;
      } else
        return who + "unknown kernel '" + k + "' (expected coulomb, gravity or yukawa)";
    } else if (kw == "order") {
      if (i + 1 >= args.size()) return who + "keyword 'order' needs a value";
      int p;
      if (!to_int(args[i + 1], p)) return who + "order '" + args[i + 1] + "' is not an integer";
      if (p < kifmm_min_order || p > kifmm_max_order)
        return who + "order " + args[i + 1] + " is out of range " +
            std::to_string(kifmm_min_order) + ".." + std::to_string(kifmm_max_order);
      s.order = p;
      i += 2;
    } else if (kw == "leaf") {
      if (i + 1 >= args.size()) return who + "keyword 'leaf' needs a value";
      int m;
      if (!to_int(args[i + 1], m)) return who + "leaf '" + args[i + 1] + "' is not an integer";
      if (m < 1 || m > 100000) return who + "leaf " + args[i + 1] + " is out of range 1..100000";
      s.leaf = m;
      i += 2;
    } else if (kw == "grid") {
      if (i + 1 >= args.size()) return who + "keyword 'grid' needs a value: auto, no or the cells per side (>= 3)";
      int k;
      if (args[i + 1] == "auto")
        s.grid = -1;
      else if (args[i + 1] == "no")
        s.grid = 0;
      else if (!to_int(args[i + 1], k))
        return who + "grid '" + args[i + 1] + "' must be auto, no or an integer";
      else if (k < kifmm_min_grid || k > kifmm_max_grid)
        return who + "grid " + args[i + 1] + " is out of range " + std::to_string(kifmm_min_grid) + ".." +
            std::to_string(kifmm_max_grid);
      else
        s.grid = k;
      i += 2;
    } else if (kw == "tune" || kw == "jeans") {
      const std::string why = yes_no(args, i, who, kw == "tune" ? s.tune : s.jeans);
      if (!why.empty()) return why;
      i += 2;
    } else if (kw == "check") {
      if (i + 2 >= args.size()) return who + "keyword 'check' needs 2 values: EVERY NSAMPLE";
      int every, n;
      if (!to_int(args[i + 1], every) || every < 0)
        return who + "check EVERY '" + args[i + 1] + "' must be an integer >= 0";
      if (!to_int(args[i + 2], n) || n < 1)
        return who + "check NSAMPLE '" + args[i + 2] + "' must be an integer >= 1";
      s.check_every = every;
      s.check_samples = n;
      i += 3;
    } else if (kw == "cache") {
      if (i + 1 >= args.size()) return who + "keyword 'cache' needs a directory or 'none'";
      s.cache_dir = args[i + 1];
      i += 2;
    } else
      break;    // not ours: LAMMPS's generic kspace_modify keywords may follow
  }
  if (i == 1) return who + "unknown keyword '" + args[1] + "'";
  consumed = (int) i;
  return "";
}

}    // namespace kifmm_lammps
