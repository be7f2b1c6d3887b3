// ekf: the motion test of one landmark (docs/design.md, "The world model"). A landmark that stands
// still is paired with innovations that form a white sequence (a consistent filter's innovations
// are uncorrelated in time); a slow mover that the update drags along is paired with innovations
// that keep one direction in the world frame. The pose's error is common to every landmark of a scan
// and is not motion, so each pairing enters as its world-frame innovation less the information-
// weighted mean of the scan's other pairs' (a scan with one pair is no evidence of motion):
//   delta_k = G_k nu_k, Sigma_k = G_k S_k G_k^T     (world frame; G the inverse observation's Jacobian)
//   d = delta_j - mean_{k != j} delta_k,  D = Sigma_j + (sum_{k != j} Sigma_k^-1)^-1
//   u <- lambda u + D^-1 d,               V <- lambda^2 V + D^-1
// For a static landmark u is Gaussian with covariance V (at most: D counts the pose's uncertainty
// that the difference removes), so t = u^T V^-1 u is chi-square with 2 degrees of freedom or below at
// every pairing: t > -2 ln(p_FA) fails with probability at most p_FA per pairing, the threshold
// from a false-alarm rate and not from a scene. lambda = kMotionFading keeps about 20 pairings.
// Five scalars per landmark (LandmarkRecord); two passes over a scan's pairs, no loop per landmark.
#pragma once

#include <cmath>

#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/math.hpp"

namespace geojcbb::ekf {

/// The fading factor of the motion test: a pairing's weight halves after about 13 pairings, so a
/// landmark's last 20 or so carry the test. Longer memory finds a slower drift and forgets a
/// stopped mover's past later; 0.95 was set before any run.
template <typename T>
inline constexpr T kMotionFading = T(0.95);

/// One landmark's evidence of motion (world frame): u and the upper triangle of V.
template <typename T>
struct MotionEvidence {
  T u[2];  ///< fading sum of Sigma^-1 delta [1/m]
  T v[3];  ///< its covariance for a static landmark: xx, xy, yy [1/m^2]
  void clear() { u[0] = u[1] = v[0] = v[1] = v[2] = T(0); }
  /// The statistic u^T V^-1 u (0 before the first pairing, or for a V that is not definite).
  T statistic() const {
    const T det = v[0] * v[2] - v[1] * v[1];
    if (!(det > T(0))) return T(0);
    const T t = (v[2] * u[0] * u[0] - T(2) * v[1] * u[0] * u[1] + v[0] * u[1] * u[1]) / det;
    return std::isfinite(t) ? t : T(0);
  }
  /// One pairing's differential innovation d in the world frame with its covariance D (upper
  /// triangle xx, xy, yy): u <- lambda u + D^-1 d, V <- lambda^2 V + D^-1. A non-finite or singular
  /// input leaves the evidence as it was. @return the statistic after it.
  T add(const T (&d)[2], const T (&D)[3]) {
    const T det = D[0] * D[2] - D[1] * D[1];
    if (!(det > T(0)) || !std::isfinite(det) || !std::isfinite(d[0] + d[1])) return statistic();
    const T i00 = D[2] / det, i01 = -D[1] / det, i11 = D[0] / det;
    const T l = kMotionFading<T>, l2 = l * l;
    u[0] = l * u[0] + i00 * d[0] + i01 * d[1];
    u[1] = l * u[1] + i01 * d[0] + i11 * d[1];
    v[0] = l2 * v[0] + i00;
    v[1] = l2 * v[1] + i01;
    v[2] = l2 * v[2] + i11;
    return statistic();
  }
  /// Into a frame rotated by R^T (ekf::Slam::reanchor: l' = R^T (l - p)): u' = R^T u, V' = R^T V R.
  void rotate(T c, T s) {
    const T u0 = c * u[0] + s * u[1], u1 = -s * u[0] + c * u[1];
    const T m00 = c * c * v[0] + T(2) * c * s * v[1] + s * s * v[2];
    const T m01 = -c * s * v[0] + (c * c - s * s) * v[1] + c * s * v[2];
    const T m11 = s * s * v[0] - T(2) * c * s * v[1] + c * c * v[2];
    u[0] = u0;
    u[1] = u1;
    v[0] = m00;
    v[1] = m01;
    v[2] = m11;
  }
};

/// One pairing's innovation in the world frame: delta = G nu and Sigma = G S G^T (upper triangle),
/// G = R(alpha) diag(1, r) the inverse observation's Jacobian at predicted range r and world bearing
/// alpha. @return false (nothing written) for a non-finite input or r <= 0.
template <typename T>
bool world_innovation(const Vec2<T>& nu, const Mat2<T>& S, T r, T alpha, T (&delta)[2], T (&Sigma)[3]) {
  if (!(r > T(0)) || !std::isfinite(nu.x() + nu.y() + alpha + r + S(0, 0) + S(0, 1) + S(1, 1))) return false;
  const T c = fmath::cos(alpha), s = fmath::sin(alpha);
  // G = [[c, -s r], [s, c r]]
  const T g00 = c, g01 = -s * r, g10 = s, g11 = c * r;
  const T s01 = T(0.5) * (S(0, 1) + S(1, 0));
  delta[0] = g00 * nu.x() + g01 * nu.y();
  delta[1] = g10 * nu.x() + g11 * nu.y();
  // G S (rows), then (G S) G^T
  const T a00 = g00 * S(0, 0) + g01 * s01, a01 = g00 * s01 + g01 * S(1, 1);
  const T a10 = g10 * S(0, 0) + g11 * s01, a11 = g10 * s01 + g11 * S(1, 1);
  Sigma[0] = a00 * g00 + a01 * g01;
  Sigma[1] = a00 * g10 + a01 * g11;
  Sigma[2] = a10 * g10 + a11 * g11;
  return true;
}

/// The threshold of the statistic for a false-alarm rate p_FA per pairing (chi-square, 2 degrees of
/// freedom: P(t > x) = exp(-x / 2)); 0 (the test off) for p_FA outside (0, 1).
template <typename T>
T motion_threshold(double p_false_alarm) {
  return p_false_alarm > 0 && p_false_alarm < 1 ? static_cast<T>(-2.0 * std::log(p_false_alarm)) : T(0);
}

}  // namespace geojcbb::ekf
