// The portable float functions (core/fmath.hpp) against the C library in double: the accuracy the
// header states, the special values, and that double still goes to the C library.
#include <doctest/doctest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>

#include "geojcbb/core/fmath.hpp"

namespace fm = geojcbb::fmath;

namespace {
// |got - ref| in units of the float spacing in ref's binade (subnormal spacing below FLT_MIN).
double ulps(float got, double ref) {
  if (ref == 0.0) return got == 0.0f ? 0.0 : std::numeric_limits<double>::infinity();
  const double spacing = std::fabs(ref) < FLT_MIN ? std::ldexp(1.0, -149) : std::ldexp(1.0, std::ilogb(ref) - 23);
  return std::fabs(static_cast<double>(got) - ref) / spacing;
}
float from_bits(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}
}  // namespace

TEST_CASE("fmath sin and cos: within 1.6 ulp from -2 pi to 2 pi and next to every zero below 4096 rad") {
  double worst = 0, worst_abs = 0;
  // Every 61st float from FLT_MIN up to 2 pi, and its negative (35 million arguments; every 7th
  // gave the same bound, 1.52 ulp, in 17 s).
  for (std::uint32_t u = 0x00800000u;; u += 61) {
    const float x = from_bits(u);
    if (!(x < 6.2832f)) break;
    for (const float y : {x, -x}) {
      worst = std::fmax(worst, ulps(fm::sin(y), std::sin(static_cast<double>(y))));
      worst = std::fmax(worst, ulps(fm::cos(y), std::cos(static_cast<double>(y))));
    }
  }
  // The 101 floats around each multiple of pi/2 below 4096 rad, where the result is near zero and
  // any error of the argument reduction shows in full.
  for (int k = 1; k < 2608; ++k) {
    float x = static_cast<float>(k * 1.57079632679489661923);
    for (int j = 0; j < 50; ++j) x = std::nextafter(x, 0.0f);
    for (int j = 0; j <= 100; ++j, x = std::nextafter(x, 1e9f)) {
      worst = std::fmax(worst, ulps(fm::sin(x), std::sin(static_cast<double>(x))));
      worst = std::fmax(worst, ulps(fm::cos(x), std::cos(static_cast<double>(x))));
    }
  }
  for (int i = -400000; i <= 400000; ++i) {  // step 0.01 rad up to 4000 rad
    const float x = static_cast<float>(i) * 0.01f;
    worst_abs = std::fmax(worst_abs, std::fabs(fm::sin(x) - std::sin(static_cast<double>(x))));
    worst_abs = std::fmax(worst_abs, std::fabs(fm::cos(x) - std::cos(static_cast<double>(x))));
  }
  CHECK(worst <= 1.6);
  CHECK(worst_abs <= 1e-7);
  // Zeros, quadrant boundaries and symmetry.
  CHECK(fm::sin(0.0f) == 0.0f);
  CHECK(std::signbit(fm::sin(-0.0f)));
  CHECK(fm::cos(0.0f) == 1.0f);
  for (float x = 0.01f; x < 20.f; x += 0.173f) {
    CHECK(fm::sin(-x) == -fm::sin(x));
    CHECK(fm::cos(-x) == fm::cos(x));
  }
  // Beyond 4096 rad: wrapped first, still a sine.
  CHECK(std::fabs(fm::sin(10000.0f) - std::sin(10000.0)) < 2e-3);
  CHECK(std::isnan(fm::sin(std::numeric_limits<float>::infinity())));
  CHECK(std::isnan(fm::cos(std::numeric_limits<float>::quiet_NaN())));
}

TEST_CASE("fmath atan2: within 3.2 ulp over all quadrants, exact special cases") {
  double worst = 0;
  for (int i = -600; i <= 600; ++i) {
    for (int j = -600; j <= 600; ++j) {
      const float y = static_cast<float>(i) * 0.0731f, x = static_cast<float>(j) * 0.0917f;
      if (x == 0.0f && y == 0.0f) continue;
      worst = std::fmax(worst, ulps(fm::atan2(y, x), std::atan2(static_cast<double>(y), static_cast<double>(x))));
    }
  }
  for (float r = 1e-6f; r < 1e6f; r *= 1.37f) {  // extreme ratios
    worst = std::fmax(worst, ulps(fm::atan2(r, 1.0f), std::atan2(static_cast<double>(r), 1.0)));
    worst = std::fmax(worst, ulps(fm::atan2(-1.0f, -r), std::atan2(-1.0, -static_cast<double>(r))));
  }
  CHECK(worst <= 3.2);
  CHECK(fm::atan2(0.0f, 1.0f) == 0.0f);
  CHECK(fm::atan2(0.0f, -1.0f) == std::atan2(0.0f, -1.0f));
  CHECK(fm::atan2(1.0f, 0.0f) == std::atan2(1.0f, 0.0f));
  CHECK(std::isnan(fm::atan2(std::numeric_limits<float>::quiet_NaN(), 1.0f)));
}

TEST_CASE("fmath exp: within 1 ulp over its normal range, 0 and infinity outside") {
  double worst = 0;
  for (int i = -873000; i <= 887000; i += 3) {
    const float x = static_cast<float>(i) * 1e-4f;
    const double e = std::exp(static_cast<double>(x));
    if (e >= FLT_MIN) worst = std::fmax(worst, ulps(fm::exp(x), e));
  }
  CHECK(worst <= 1.0);
  CHECK(fm::exp(0.0f) == 1.0f);
  CHECK(fm::exp(-100.0f) == 0.0f);
  CHECK(std::isinf(fm::exp(100.0f)));
  CHECK(std::isnan(fm::exp(std::numeric_limits<float>::quiet_NaN())));
}

TEST_CASE("fmath log: within 0.85 ulp on every float from 0.5 to 2 and from 1e-37 to 1e37") {
  double worst = 0;
  for (std::uint32_t u = 0x3F000000u; u < 0x40000000u; ++u) {  // every float in [0.5, 2)
    const float x = from_bits(u);
    if (x != 1.0f) worst = std::fmax(worst, ulps(fm::log(x), std::log(static_cast<double>(x))));
  }
  for (int i = 0; i <= 400000; ++i) {
    const float x = std::pow(10.0f, -37.0f + static_cast<float>(i) * (74.0f / 400000.0f));
    worst = std::fmax(worst, ulps(fm::log(x), std::log(static_cast<double>(x))));
  }
  CHECK(worst <= 0.85);
  CHECK(fm::log(1.0f) == 0.0f);
  CHECK(std::isinf(fm::log(0.0f)));
  CHECK(std::isnan(fm::log(-1.0f)));
  const float tiny = 1e-40f;  // subnormal input
  CHECK(ulps(fm::log(tiny), std::log(static_cast<double>(tiny))) <= 0.85);
}

TEST_CASE("fmath: double goes to the C library") {
  for (double x = -7.0; x < 7.0; x += 0.31) {
    CHECK(fm::sin(x) == std::sin(x));
    CHECK(fm::cos(x) == std::cos(x));
    CHECK(fm::atan2(x, 0.7) == std::atan2(x, 0.7));
    CHECK(fm::exp(x) == std::exp(x));
  }
  CHECK(fm::log(2.5) == std::log(2.5));
}
