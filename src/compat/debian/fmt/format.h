// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Shim for LAMMPS 29Sep2021 headers on Debian.
//
// Debian's liblammps-dev includes "fmt/format.h" without shipping it; the library itself was
// built with a bundled fmt 7 (namespace fmt::v7_lmp). We compile against Debian's fmt 9 and
// add back the one helper that LAMMPS's headers use and fmt 9 dropped. The fmt-taking entry
// points of LAMMPS (Error::_all and friends) are defined for fmt 9 types in
// lammps_fmt_entry_points.cpp; they format here and forward to LAMMPS's std::string overloads.
#pragma once

#include_next <fmt/format.h>

namespace fmt {
inline namespace v9 {
template <typename... Args, typename S>
inline auto make_args_checked(const S &, const remove_reference_t<Args> &...args)
{
  return make_format_args(args...);
}
}    // namespace v9
}    // namespace fmt
