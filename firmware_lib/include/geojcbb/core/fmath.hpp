// core: portable elementary functions for float, so a scan gives the same bits on every target.
//
// The C libraries differ in the last bit of sinf, cosf, atan2f, expf and logf (glibc on x86-64 picks
// FMA variants at run time; picolibc on the Cortex-M4F has its own). The firmware promises results
// equal, bit for bit, to the host's float pipeline (docs/design.md, "Same bits on host and
// device"), so float goes through the functions below: plain float additions and multiplications
// in a fixed order, which IEEE-754 rounds identically everywhere as long as the compiler neither
// contracts a*b+c into a fused multiply-add (-ffp-contract=off, which geojcbb::firmware's CMake
// target gives every user) nor
// reorders (no -ffast-math). sqrt and remainder are exactly rounded by IEEE-754 and stay std::.
// double (the host's evaluation Scalar) keeps the C library.
//
// Method: Cody-Waite argument reduction and minimax polynomials with Cephes' published
// coefficients (S. L. Moshier, "Methods and Programs for Mathematical Functions", 1989). Accuracy
// against a double reference, in ulp of the result's binade (tests/firmware_lib/core/
// test_fmath.cpp): sin and cos within 1.6 ulp on [-2 pi, 2 pi] and next to every zero below 4096
// rad; atan2 within 3.2 ulp; exp within 1 ulp; log within 0.85 ulp (every float in [0.5, 2)).
// Bounds: no loops.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace geojcbb::fmath {

namespace detail {

inline float from_bits(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}
inline std::uint32_t to_bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

// pi/2 in four parts of at most 11 significant bits (the last one rounded): for a quadrant index
// below 2^12 every product with the first three is exact, so the reduced argument is accurate to
// float even next to a zero of sin or cos (pi/2 - the four parts: 8e-20).
constexpr float kPio2Hi = 1.5703125f;
constexpr float kPio2Mid = 4.837512969970703125e-4f;
constexpr float kPio2Lo1 = 7.549533620476722717e-8f;
constexpr float kPio2Lo2 = 2.5633440682570896e-12f;
constexpr float kTwoOverPi = 0.636619772367581343f;
// Up to this |x| (quadrant index < 2^12) the reduction is accurate to float; beyond it x is first wrapped with
// std::remainder by float(2 pi) (exact, hence portable; the angle error grows as |x| * 1.7e-7).
// Angles in this library are wrapped to a few pi, so that path is for robustness only.
constexpr float kMaxReduced = 4096.0f;
constexpr float kTwoPiF = 6.28318530717958647692f;

// sin and cos on [-pi/4, pi/4].
inline float sin_kernel(float r) {
  const float z = r * r;
  return ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * r + r;
}
inline float cos_kernel(float r) {
  const float z = r * r;
  return ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z - 0.5f * z + 1.0f;
}

// Reduces x to r in [-pi/4, pi/4] with x = q * pi/2 + r; returns q mod 4.
inline int reduce(float x, float& r) {
  const float k = x * kTwoOverPi;
  const int q = static_cast<int>(k >= 0.0f ? k + 0.5f : k - 0.5f);
  const float fq = static_cast<float>(q);
  r = (((x - fq * kPio2Hi) - fq * kPio2Mid) - fq * kPio2Lo1) - fq * kPio2Lo2;
  return q & 3;
}

}  // namespace detail

/// sin(x); NaN for NaN and infinities.
inline float sin(float x) {
  if (!std::isfinite(x)) return x - x;
  if (x == 0.0f) return x;  // keeps the sign of zero
  if (!(std::fabs(x) <= detail::kMaxReduced)) x = std::remainder(x, detail::kTwoPiF);
  float r;
  switch (detail::reduce(x, r)) {
    case 0: return detail::sin_kernel(r);
    case 1: return detail::cos_kernel(r);
    case 2: return -detail::sin_kernel(r);
    default: return -detail::cos_kernel(r);
  }
}

/// cos(x); NaN for NaN and infinities.
inline float cos(float x) {
  if (!std::isfinite(x)) return x - x;
  if (!(std::fabs(x) <= detail::kMaxReduced)) x = std::remainder(x, detail::kTwoPiF);
  float r;
  switch (detail::reduce(x, r)) {
    case 0: return detail::cos_kernel(r);
    case 1: return -detail::sin_kernel(r);
    case 2: return -detail::cos_kernel(r);
    default: return detail::sin_kernel(r);
  }
}

/// atan(x) for x >= 0.
inline float atan_nonneg(float x) {
  constexpr float kTan3Pi8 = 2.414213562373095f;
  constexpr float kTanPi8 = 0.4142135623730950f;
  float y0 = 0.0f;
  if (x > kTan3Pi8) {
    y0 = 1.5707963267948966f;
    x = -1.0f / x;
  } else if (x > kTanPi8) {
    y0 = 0.7853981633974483f;
    x = (x - 1.0f) / (x + 1.0f);
  }
  const float z = x * x;
  return y0 +
         ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * x + x);
}

/// atan2(y, x) in [-pi, pi], with the C library's conventions for zeros (signs kept) and
/// infinities; NaN in, NaN out.
inline float atan2(float y, float x) {
  constexpr float kPi = 3.14159265358979323846f;
  constexpr float kPio2 = 1.57079632679489661923f;
  if (std::isnan(x) || std::isnan(y)) return x + y;
  if (std::isinf(x) || std::isinf(y) || x == 0.0f || y == 0.0f) return std::atan2(y, x);  // exact cases
  const float ax = std::fabs(x), ay = std::fabs(y);
  float a;
  if (ay <= ax) {
    a = atan_nonneg(ay / ax);
  } else {
    a = kPio2 - atan_nonneg(ax / ay);
  }
  if (x < 0.0f) a = kPi - a;
  return y < 0.0f ? -a : a;
}

/// exp(x); 0 below -87.3 (no subnormals), +inf above 88.7.
inline float exp(float x) {
  if (std::isnan(x)) return x;
  if (x > 88.72283905206835f) return std::numeric_limits<float>::infinity();
  if (x < -87.33654475055310898657f) return 0.0f;
  const float k = x * 1.44269504088896341f;
  const int n = static_cast<int>(k >= 0.0f ? k + 0.5f : k - 0.5f);
  const float fn = static_cast<float>(n);
  const float r = (x - fn * 0.693359375f) - fn * -2.12194440e-4f;
  const float z = r * r;
  const float p = (((((1.9875691500e-4f * r + 1.3981999507e-3f) * r + 8.3334519073e-3f) * r + 4.1665795894e-2f) * r +
                    1.6666665459e-1f) *
                       r +
                   5.0000001201e-1f) *
                      z +
                  r + 1.0f;
  // 2^n in two factors so n = 128 (x just under 88.72) and n = -126 stay representable.
  const int h = n / 2;
  const float s1 = detail::from_bits(static_cast<std::uint32_t>(h + 127) << 23);
  const float s2 = detail::from_bits(static_cast<std::uint32_t>(n - h + 127) << 23);
  return p * s1 * s2;
}

/// log(x); -inf at 0, NaN below 0, +inf at +inf.
inline float log(float x) {
  if (!(x > 0.0f) || std::isinf(x)) return std::log(x);  // 0, negative, NaN, inf: exact cases
  int e = 0;
  if (x < std::numeric_limits<float>::min()) {  // subnormal: scale into the normal range
    x *= 8388608.0f;                            // 2^23
    e = -23;
  }
  const std::uint32_t u = detail::to_bits(x);
  e += static_cast<int>((u >> 23) & 0xFF) - 126;
  float m = detail::from_bits((u & 0x007FFFFFu) | 0x3F000000u);  // in [0.5, 1)
  if (m < 0.70710678118654752f) {
    e -= 1;
    m = m + m - 1.0f;
  } else {
    m = m - 1.0f;
  }
  const float z = m * m;
  float y = ((((((((7.0376836292e-2f * m - 1.1514610310e-1f) * m + 1.1676998740e-1f) * m - 1.2420140846e-1f) * m +
                 1.4249322787e-1f) *
                    m -
                1.6668057665e-1f) *
                   m +
               2.0000714765e-1f) *
                  m -
              2.4999993993e-1f) *
                 m +
             3.3333331174e-1f) *
            m * z;
  const float fe = static_cast<float>(e);
  y += -2.12194440e-4f * fe;
  y += -0.5f * z;
  return (m + y) + 0.693359375f * fe;
}

// The library's entry points: float goes through the portable versions, double (host) through the
// C library.
inline double sin(double x) { return std::sin(x); }
inline double cos(double x) { return std::cos(x); }
inline double atan2(double y, double x) { return std::atan2(y, x); }
inline double exp(double x) { return std::exp(x); }
inline double log(double x) { return std::log(x); }

}  // namespace geojcbb::fmath
