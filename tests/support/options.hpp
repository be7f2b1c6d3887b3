// Tests: settings with one option moved to another value inside its range, for the tests that
// prove every option reaches where it should (the C boundary, CONFIG, a device over the link).
#pragma once

#include <cmath>
#include <type_traits>

#include "geojcbb/core/settings.hpp"

namespace geojcbb::test {

/// A value of the option other than `v`, inside its range (and exact in float32).
template <typename V>
V other_value(const options::Info& info, V v) {
  if constexpr (std::is_same<V, bool>::value) {
    return !v;
  } else if constexpr (std::is_enum<V>::value) {
    return static_cast<V>((static_cast<int>(v) + 1) % kStrategyCount);
  } else {
    const options::Range& r = info.range;
    const double d = static_cast<double>(v);
    double x = d + 1;
    switch (r.kind) {
      case options::RangeKind::kANY:
      case options::RangeKind::kGT:
      case options::RangeKind::kGE: x = d >= 1 ? std::floor(2 * d + 1) : 1; break;
      default: {
        x = std::floor(r.lo) + 1;
        if (!(x < r.hi)) x = 0.5 * (r.lo + r.hi);
        if (x == d) x = 0.25 * r.lo + 0.75 * r.hi;
        if (std::is_integral<V>::value) x = std::floor(x);
      }
    }
    return static_cast<V>(x);
  }
}

/// The settings with option k set to another in-range value.
template <typename T>
StepSettings<T> with_other(int k) {
  StepSettings<T> s;
  for_each_option(s, [&](const options::Info& info, auto& v) {
    if (&info - options::kInfo == k) v = other_value(info, v);
  });
  return s;
}

/// The settings as a float device receives them: each level and real value rounded to float32.
template <typename T, typename S>
StepSettings<T> at_wire_precision(const S& s) {
  StepSettings<T> out;
  for_each_option_pair(out, s, [](const options::Info&, auto& o, const auto& v) {
    using O = std::remove_reference_t<decltype(o)>;
    if constexpr (std::is_floating_point<O>::value) {
      o = static_cast<O>(static_cast<float>(v));
    } else {
      o = options::convert<O>(v);
    }
  });
  return out;
}

}  // namespace geojcbb::test
