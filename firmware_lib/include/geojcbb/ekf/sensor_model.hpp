// ekf: a calibrated range-bearing sensor: corrects a raw measurement's systematic error and gives
// its covariance R, before association and update. Fitted to MRCLAM's cameras (docs/mrclam.md):
//   range:    r_raw = r (1 + c0 + c1 b + c2 b^2) + e_r,   e_r ~ N(0, s_r0^2 + (k_r r)^2)
//   bearing:  b_raw = b + b0 + e_b,                          e_b ~ N(0, s_b^2)
// so z = (r_raw / (1 + c0 + c1 b + c2 b^2), b_raw - b0) with b = b_raw - b0, and R = diag(...) at r.
// A camera that measures range from a target's apparent size errs in proportion to the range, and a
// lens errs more towards the image's edges: hence the relative, bearing-dependent bias. The default
// is the identity correction with a constant R. O(1), no heap.
#pragma once

#include "geojcbb/core/math.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb::ekf {

template <typename T>
struct RangeBearingModel {
  T range_rel_bias0 = T(0);           ///< c0: relative range bias at bearing 0
  T range_rel_bias1_per_rad = T(0);   ///< c1: its slope in the bearing [1/rad]
  T range_rel_bias2_per_rad2 = T(0);  ///< c2: its curvature in the bearing [1/rad^2]
  T bearing_bias_rad = T(0);          ///< b0 [rad]
  T sigma_range_m = T(0.1);           ///< s_r0: the constant part of the range std [m]
  T sigma_range_rel = T(0);           ///< k_r: the part proportional to the range [m/m]
  T sigma_bearing_rad = T(0.01);      ///< s_b [rad]

  /// True when every field is finite, the stds are non-negative and R is positive definite at
  /// every range (s_r0 > 0 or k_r > 0 with ranges > 0; s_b > 0).
  bool valid() const {
    const T f[] = {range_rel_bias0, range_rel_bias1_per_rad, range_rel_bias2_per_rad2, bearing_bias_rad,
                   sigma_range_m,   sigma_range_rel,         sigma_bearing_rad};
    for (const T v : f)  // <= 7
      if (!std::isfinite(v)) return false;
    return sigma_range_m >= T(0) && sigma_range_rel >= T(0) && sigma_range_m + sigma_range_rel > T(0) &&
           sigma_bearing_rad > T(0);
  }

  /// Corrects a raw measurement (range [m], bearing [rad]) and gives its covariance.
  /// @param[out] z  the corrected measurement; written only on kOk
  /// @param[out] R  its covariance (diagonal, positive definite); written only on kOk
  /// @return kOk; kNonFinite for a NaN or Inf; kInvalidInput for a model that is not valid(), a
  ///         range that is not positive, or a correction factor that is not positive.
  [[nodiscard]] Status correct(const Vec2<T>& raw, Vec2<T>& z, Mat2<T>& R) const {
    if (!raw.allFinite()) return Status::kNonFinite;
    if (!valid() || !(raw.x() > T(0))) return Status::kInvalidInput;
    const T b = wrap_angle(raw.y() - bearing_bias_rad);
    const T factor = T(1) + range_rel_bias0 + range_rel_bias1_per_rad * b + range_rel_bias2_per_rad2 * b * b;
    if (!(factor > T(0))) return Status::kInvalidInput;
    const T r = raw.x() / factor;
    const T sr = sigma_range_rel * r;
    z = Vec2<T>(r, b);
    R << sigma_range_m * sigma_range_m + sr * sr, T(0),  //
        T(0), sigma_bearing_rad * sigma_bearing_rad;
    return Status::kOk;
  }
};

}  // namespace geojcbb::ekf
