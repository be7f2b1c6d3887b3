// core: small math shared by every stage: fixed-size Eigen aliases, angle wrapping into (-pi, pi],
// finiteness and covariance checks. No allocation; every loop is bounded by a matrix size.
#pragma once

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb {

template <typename T>
using Vec2 = Eigen::Matrix<T, 2, 1>;
template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat2 = Eigen::Matrix<T, 2, 2>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Mat23 = Eigen::Matrix<T, 2, 3>;
template <typename T>
using Mat32 = Eigen::Matrix<T, 3, 2>;

template <typename T>
constexpr T kPi = T(3.14159265358979323846264338327950288L);
template <typename T>
constexpr T kTwoPi = T(6.28318530717958647692528676655900577L);

/// Wraps an angle into (-pi, pi]. Inputs already in range return unchanged (the common case for
/// innovations); others go through std::remainder (no loop).
template <typename T>
T wrap_angle(T a) {
  if (a > -kPi<T> && a <= kPi<T>) return a;
  T r = std::remainder(a, kTwoPi<T>);  // in [-pi, pi]
  if (r <= -kPi<T>) r += kTwoPi<T>;
  return r;
}

template <typename Derived>
bool all_finite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

/// Relative tolerance for "symmetric" and "positive" checks on covariances computed in Scalar T:
/// products like H P H^T carry rounding of a few hundred ulps.
template <typename T>
constexpr T kCovarianceTolerance = T(1024) * std::numeric_limits<T>::epsilon();

/// True when |a - b| is within rounding of their magnitudes. Both are halved first (exact for normal
/// numbers), so that no finite pair overflows the test: 3e38 and -3e38 in float are not "nearly
/// equal" (unhalved, inf <= inf said they were).
template <typename T>
bool nearly_equal(T a, T b) {
  const T ha = T(0.5) * a, hb = T(0.5) * b;
  return std::abs(ha - hb) <= kCovarianceTolerance<T> * (std::abs(ha) + std::abs(hb)) + std::numeric_limits<T>::min();
}

/// The symmetric part (M + M^T) / 2 of a small square matrix, without overflow at any finite
/// magnitude: the diagonal is copied, each off-diagonal pair becomes a/2 + b/2. For normal numbers
/// this equals (M + M^T) / 2 bit for bit (halving is exact, and so is doubling a + a); unlike it, a
/// finite variance above half the scalar's max stays finite (fuzz_node's finding: RESET with a
/// variance of 2e38 in float made P infinite).
template <typename T, int N>
Eigen::Matrix<T, N, N> symmetric_part(const Eigen::Matrix<T, N, N>& m) {
  Eigen::Matrix<T, N, N> s;
  for (int r = 0; r < N; ++r) {  // <= N
    s(r, r) = m(r, r);
    for (int c = 0; c < r; ++c) {  // <= N
      const T v = T(0.5) * m(r, c) + T(0.5) * m(c, r);
      s(r, c) = v;
      s(c, r) = v;
    }
  }
  return s;
}

/// A 2x2 covariance is acceptable as a measurement noise R when finite, symmetric and positive
/// definite (both leading minors strictly positive).
template <typename T>
bool is_spd(const Mat2<T>& m) {
  return m.allFinite() && nearly_equal(m(0, 1), m(1, 0)) && m(0, 0) > T(0) &&
         m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0) > T(0);
}

/// A 3x3 covariance is positive definite beyond rounding: its correlation matrix (scale-free, so no
/// overflow or underflow at any magnitude of the variances) has both leading minors past the
/// first above 64 epsilon. (Sylvester on the raw entries overflows at 1e20 in float and calls a
/// matrix that rounding made singular definite.)
template <typename T>
bool is_spd_scaled(const Mat3<T>& m) {
  T d[3];
  for (int i = 0; i < 3; ++i) {  // <= 3
    if (!(m(i, i) > T(0)) || !std::isfinite(m(i, i))) return false;
    d[i] = T(1) / std::sqrt(m(i, i));
  }
  const T a = m(0, 1) * d[0] * d[1], b = m(0, 2) * d[0] * d[2], c = m(1, 2) * d[1] * d[2];
  const T tol = T(64) * std::numeric_limits<T>::epsilon();
  const T m2 = T(1) - a * a;
  const T m3 = T(1) + T(2) * a * b * c - a * a - b * b - c * c;
  return m2 > tol && m3 > tol;  // false for NaN
}

/// A 2x2 covariance [a b; b d] is positive definite beyond rounding: both variances positive and
/// finite, and the correlation b / sqrt(a d) (computed without overflow) at most 1 - 64 epsilon in
/// squared magnitude, as is_spd_scaled for 3x3.
template <typename T>
bool is_spd_scaled(T a, T b, T d) {
  if (!(a > T(0)) || !(d > T(0)) || !std::isfinite(a) || !std::isfinite(d) || !std::isfinite(b)) return false;
  const T r = b * (T(1) / std::sqrt(a)) * (T(1) / std::sqrt(d));
  return T(1) - r * r > T(64) * std::numeric_limits<T>::epsilon();  // false for NaN
}

/// A 2x2 block of a predicted-measurement covariance C may be singular (a perfectly known feature)
/// but never indefinite.
template <typename T>
bool is_psd(const Mat2<T>& m) {
  const T det = m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0);
  const T scale = m(0, 0) * m(1, 1);
  return m.allFinite() && nearly_equal(m(0, 1), m(1, 0)) && m(0, 0) >= T(0) && m(1, 1) >= T(0) &&
         det >= -kCovarianceTolerance<T> * scale;
}

}  // namespace geojcbb
