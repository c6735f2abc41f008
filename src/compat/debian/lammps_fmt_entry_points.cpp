// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Definitions of LAMMPS's fmt-taking entry points for Debian's fmt 9 types.
//
// liblammps exports these functions only for its private fmt 7 (fmt::v7_lmp) types, so calls
// like error->all(FLERR, "bad {}", x) made from code compiled against fmt 9 need these. Each
// one formats the message and forwards it to the std::string overload that liblammps exports.
// A malformed format string is reported as the error text instead of throwing.
#include "error.h"
#include "utils.h"

using namespace LAMMPS_NS;

namespace {
std::string format_or_explain(fmt::string_view format, fmt::format_args args)
{
  try {
    return fmt::vformat(format, args);
  } catch (fmt::format_error &e) {
    return std::string("(bad format string '") + std::string(format.data(), format.size()) +
        "': " + e.what() + ")";
  }
}
}    // namespace

void Error::_all(const std::string &file, int line, fmt::string_view format,
                 fmt::format_args args)
{
  all(file, line, format_or_explain(format, args));
}

void Error::_one(const std::string &file, int line, fmt::string_view format,
                 fmt::format_args args)
{
  one(file, line, format_or_explain(format, args));
}

void Error::_warning(const std::string &file, int line, fmt::string_view format,
                     fmt::format_args args)
{
  warning(file, line, format_or_explain(format, args));
}

void Error::_message(const std::string &file, int line, fmt::string_view format,
                     fmt::format_args args)
{
  message(file, line, format_or_explain(format, args));
}

void utils::fmtargs_logmesg(LAMMPS *lmp, fmt::string_view format, fmt::format_args args)
{
  logmesg(lmp, format_or_explain(format, args));
}
