// ekf: the motion models over one odometry interval, with their analytic Jacobians.
// The velocity model of a differential-drive robot, with midpoint heading:
//   x' = x + v dt cos(theta + w dt / 2),  y' = y + v dt sin(theta + w dt / 2),  theta' = theta + w dt
// (inputs are the commanded (v, w), as the MRCLAM odometry files give them), and the pose increment
// (wheel odometry, a vehicle model, a ROS odometry message's delta): (dx, dy, dtheta) in the robot's
// frame at the start of the interval, with its full 3x3 covariance, composed onto the pose:
//   x' = x + cos(theta) dx - sin(theta) dy,  y' = y + sin(theta) dx + cos(theta) dy,  theta' = theta + dtheta
#pragma once

#include "geojcbb/core/math.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb::ekf {

/// One odometry interval.
template <typename T>
struct Odometry {
  T v_mps{};          ///< forward velocity [m/s]
  T w_radps{};        ///< angular velocity [rad/s]
  T dt_s{};           ///< interval [s], >= 0
  T sigma_v_mps{};    ///< standard deviation of v over the interval [m/s], > 0
  T sigma_w_radps{};  ///< standard deviation of w over the interval [rad/s], > 0
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

/// One odometry interval as a pose increment in the robot's frame at its start.
template <typename T>
struct PoseIncrement {
  T dx_m{};                       ///< forward [m]
  T dy_m{};                       ///< to the left [m]
  T dtheta_rad{};                 ///< turn, counter-clockwise [rad]
  Mat3<T> cov = Mat3<T>::Zero();  ///< of (dx, dy, dtheta): finite, symmetric, positive semi-definite
};

/// Composes the increment onto the pose.
/// @param[out] J_x_pose  3x3 Jacobian with respect to the pose; may be null
/// @param[out] J_x_u     3x3 Jacobian with respect to (dx, dy, dtheta); may be null
template <typename T>
Pose2<T> compose(const Pose2<T>& x, const PoseIncrement<T>& u, Mat3<T>* J_x_pose = nullptr, Mat3<T>* J_x_u = nullptr) {
  const T c = fmath::cos(x.theta);
  const T s = fmath::sin(x.theta);
  const T ddx = c * u.dx_m - s * u.dy_m, ddy = s * u.dx_m + c * u.dy_m;
  if (J_x_pose != nullptr) {
    *J_x_pose << T(1), T(0), -ddy,  //
        T(0), T(1), ddx,            //
        T(0), T(0), T(1);
  }
  if (J_x_u != nullptr) {
    *J_x_u << c, -s, T(0),  //
        s, c, T(0),         //
        T(0), T(0), T(1);
  }
  return {x.x + ddx, x.y + ddy, wrap_angle(x.theta + u.dtheta_rad)};
}

/// An increment's covariance is acceptable when finite, symmetric and positive semi-definite
/// (every principal minor at least -kCovarianceTolerance times its scale; a zero covariance, an
/// exact increment, is accepted).
template <typename T>
bool is_psd3(const Mat3<T>& m) {
  if (!m.allFinite()) return false;
  for (int r = 0; r < 3; ++r) {    // <= 3
    for (int c = 0; c < r; ++c) {  // <= 3
      if (!nearly_equal(m(r, c), m(c, r))) return false;
    }
    if (m(r, r) < T(0)) return false;
  }
  const T tol = kCovarianceTolerance<T>;
  for (int a = 0; a < 3; ++a) {        // <= 3: the 2x2 principal minors
    for (int b = a + 1; b < 3; ++b) {  // <= 3
      if (m(a, a) * m(b, b) - m(a, b) * m(a, b) < -tol * m(a, a) * m(b, b)) return false;
    }
  }
  // The determinant by cofactors (no Eigen/LU on the device).
  const T det = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0)) +
                m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
  return det >= -tol * m(0, 0) * m(1, 1) * m(2, 2);
}

/// A calibrated drive: the commanded (v, w) scaled to the motion they produce, and a process noise
/// that grows with the motion and with time (white over the interval, so variances add with dt):
///   v = scale_v v_cmd,  w = scale_w w_cmd
///   var(v dt) = (alpha_v^2 v^2 + q_v) dt,   var(w dt) = (alpha_w^2 w^2 + alpha_wv^2 v^2 + q_w) dt
/// alpha_v: slip along the path; alpha_w: error of a turn; alpha_wv: heading drift while driving
/// straight; q_v, q_w: what a standing robot still does (vibration, the command's latency). The
/// default is the identity scale with no noise. Fitted to MRCLAM in docs/mrclam.md.
template <typename T>
struct OdometryModel {
  T scale_v = T(1);
  T scale_w = T(1);
  T alpha_v_sqrt_s = T(0);          ///< [sqrt(s)]
  T q_v_m2ps = T(0);                ///< [m^2/s]
  T alpha_w_sqrt_s = T(0);          ///< [sqrt(s)]
  T alpha_wv_rad_sqrt_s_pm = T(0);  ///< [rad sqrt(s) / m]
  T q_w_rad2ps = T(0);              ///< [rad^2/s]

  bool valid() const {
    const T f[] = {scale_v, scale_w, alpha_v_sqrt_s, q_v_m2ps, alpha_w_sqrt_s, alpha_wv_rad_sqrt_s_pm, q_w_rad2ps};
    for (const T v : f)  // <= 7
      if (!std::isfinite(v) || v < T(0)) return false;
    return true;
  }

  /// The interval's odometry for the filter: scaled velocities and their standard deviations.
  /// @param[out] out  written only on kOk (dt = 0 gives zero standard deviations)
  /// @return kOk; kNonFinite; kInvalidInput for dt < 0 or a model that is not valid().
  [[nodiscard]] Status odometry(T v_cmd_mps, T w_cmd_radps, T dt_s, Odometry<T>& out) const {
    if (!std::isfinite(v_cmd_mps) || !std::isfinite(w_cmd_radps) || !std::isfinite(dt_s)) return Status::kNonFinite;
    if (!(dt_s >= T(0)) || !valid()) return Status::kInvalidInput;
    const T v = scale_v * v_cmd_mps;
    const T w = scale_w * w_cmd_radps;
    T sv = T(0), sw = T(0);
    if (dt_s > T(0)) {  // std of v = std(v dt) / dt = sqrt(rate / dt)
      const T aw = alpha_w_sqrt_s * w, awv = alpha_wv_rad_sqrt_s_pm * v, av = alpha_v_sqrt_s * v;
      sv = std::sqrt((av * av + q_v_m2ps) / dt_s);
      sw = std::sqrt((aw * aw + awv * awv + q_w_rad2ps) / dt_s);
    }
    out = Odometry<T>{v, w, dt_s, sv, sw};
    return Status::kOk;
  }
};

}  // namespace geojcbb::ekf
