// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// How a kernel's operators depend on the box size (level): detects the optional members
// described in kernels.h and produces, for a box of half-width h, the unit-box kernel
// (as a plain function of r2 in unit coordinates, plus a cache id) and the scale s with
//   G(h u) = s * G_unit(u).
#pragma once

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <type_traits>
#include <typeinfo>

namespace kifmm {

// A kernel in unit-box coordinates, type-erased: only used by the (cold) operator setup.
// shape: the half-widths of the unit box per axis (largest 1; cubes: 1 1 1), RootBox::shape.
struct UnitKernel {
  std::function<double(double r2)> g;    // G_unit(sqrt(r2)), r2 > 0
  std::string id;                        // unique, used as cache key (shape included)
  double shape[3] = {1.0, 1.0, 1.0};
  bool cubic() const { return shape[0] == 1.0 && shape[1] == 1.0 && shape[2] == 1.0; }
};

namespace detail {
template <class K, class = void> struct is_homogeneous : std::false_type {};
template <class K>
struct is_homogeneous<K, std::void_t<decltype(K::homogeneous), decltype(K::degree)>>
    : std::integral_constant<bool, K::homogeneous> {};
template <class K, class = void> struct has_rescaled : std::false_type {};
template <class K>
struct has_rescaled<K, std::void_t<decltype(std::declval<const K &>().rescaled(1.0, std::declval<double &>()))>>
    : std::true_type {};
template <class K, class = void> struct has_id : std::false_type {};
template <class K>
struct has_id<K, std::void_t<decltype(std::declval<const K &>().id())>> : std::true_type {};
}    // namespace detail

template <class K> std::string kernel_id(const K &k)
{
  if constexpr (detail::has_id<K>::value) return k.id();
  else return std::string("user_") + typeid(K).name();
}

// True when one operator set serves every level.
template <class K> constexpr bool level_independent_operators()
{
  return detail::is_homogeneous<K>::value;
}

namespace detail {
template <class K> UnitKernel unit_kernel_of(const K &k, double h, double &s)
{
  if constexpr (detail::is_homogeneous<K>::value) {
    s = std::pow(h, K::degree);
    return UnitKernel{[k](double r2) { return k.value(r2, 1.0 / std::sqrt(r2)); }, kernel_id(k)};
  } else if constexpr (detail::has_rescaled<K>::value) {
    auto ku = k.rescaled(h, s);
    return UnitKernel{[ku](double r2) { return ku.value(r2, 1.0 / std::sqrt(r2)); }, kernel_id(ku)};
  } else {
    s = 1.0;
    char buf[64];
    std::snprintf(buf, sizeof buf, "_h%a", h);
    return UnitKernel{[k, h](double r2) {
                        const double R2 = r2 * h * h;
                        return k.value(R2, 1.0 / std::sqrt(R2));
                      },
                      kernel_id(k) + buf};
  }
}
}    // namespace detail

// Unit kernel of boxes of half-width h (times shape[d] along axis d; null: cubes).
template <class K> UnitKernel make_unit_kernel(const K &k, double h, double &s, const double *shape = nullptr)
{
  UnitKernel u = detail::unit_kernel_of(k, h, s);
  if (shape && !(shape[0] == 1.0 && shape[1] == 1.0 && shape[2] == 1.0)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "_box%a_%a_%a", shape[0], shape[1], shape[2]);
    u.id += buf;
    for (int d = 0; d < 3; ++d) u.shape[d] = shape[d];
  }
  return u;
}

}    // namespace kifmm
