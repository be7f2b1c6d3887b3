// ekf: the velocity motion model of a differential-drive robot over one odometry interval, with
// midpoint heading, and its analytic Jacobians.
//   x' = x + v dt cos(theta + w dt / 2),  y' = y + v dt sin(theta + w dt / 2),  theta' = theta + w dt
// Inputs are the commanded (v, w), as the MRCLAM odometry files give them.
#pragma once

#include "geojcbb/core/range_bearing.hpp"

namespace geojcbb::ekf {

/// One odometry interval.
template <typename T>
struct Odometry {
  T v_mps{};             ///< forward velocity [m/s]
  T w_radps{};           ///< angular velocity [rad/s]
  T dt_s{};              ///< interval [s], >= 0
  T sigma_v_mps{};       ///< standard deviation of v over the interval [m/s], > 0
  T sigma_w_radps{};     ///< standard deviation of w over the interval [rad/s], > 0
};

/// Applies the motion model.
/// @param[out] J_x_pose  3x3 Jacobian with respect to the pose; may be null
/// @param[out] J_x_u     3x2 Jacobian with respect to (v, w); may be null
template <typename T>
Pose2<T> move(const Pose2<T>& x, const Odometry<T>& u, Mat3<T>* J_x_pose = nullptr, Mat32<T>* J_x_u = nullptr) {
  const T a = x.theta + T(0.5) * u.w_radps * u.dt_s;
  const T c = fmath::cos(a);
  const T s = fmath::sin(a);
  const T d = u.v_mps * u.dt_s;
  if (J_x_pose != nullptr) {
    *J_x_pose << T(1), T(0), -d * s,  //
        T(0), T(1), d * c,            //
        T(0), T(0), T(1);
  }
  if (J_x_u != nullptr) {
    const T h = T(0.5) * u.dt_s;
    *J_x_u << u.dt_s * c, -d * s * h,  //
        u.dt_s * s, d * c * h,         //
        T(0), u.dt_s;
  }
  return {x.x + d * c, x.y + d * s, wrap_angle(x.theta + u.w_radps * u.dt_s)};
}

}  // namespace geojcbb::ekf
