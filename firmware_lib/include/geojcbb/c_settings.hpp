// The C API's boundary: geojcbb_settings (geojcbb.h) and geojcbb::StepSettings<float>, both
// generated from the option table (core/options.h), converted member by member by the same table.
// The C API (src/c_api.cpp) and its test's C++ reference (tests/c_api) both use these two functions,
// so the test's reference is the product's own conversion, not a copy of it.
#pragma once

#include "geojcbb.h"
#include "geojcbb/core/settings.hpp"

namespace geojcbb::c_boundary {

/// Written in place: no temporary (a caller with a tight stack frame, geojcbb_slam_configure).
inline void from_c(const geojcbb_settings& c, StepSettings<float>& s) {
#define GEOJCBB_FROM_C(TYPE, name, def, range, unit, cli, doc) \
  s.name = options::convert<typename options::Types<float>::TYPE>(c.name);
  GEOJCBB_OPTIONS(GEOJCBB_FROM_C)
#undef GEOJCBB_FROM_C
}

inline StepSettings<float> from_c(const geojcbb_settings& c) {
  StepSettings<float> s;
  from_c(c, s);
  return s;
}

inline geojcbb_settings to_c(const StepSettings<float>& s) {
  geojcbb_settings c;
#define GEOJCBB_TO_C(TYPE, name, def, range, unit, cli, doc) c.name = options::convert<GEOJCBB_C_TYPE_##TYPE>(s.name);
  GEOJCBB_OPTIONS(GEOJCBB_TO_C)
#undef GEOJCBB_TO_C
  return c;
}

}  // namespace geojcbb::c_boundary
