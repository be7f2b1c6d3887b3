// core: the range-bearing sensor model z = h(x_r, l) of a 2D laser at the robot's origin, its inverse
// (a landmark from a pose and a measurement) and their analytic Jacobians, named J_out_in.
//   h(x_r, l) = [ sqrt(dx^2 + dy^2) ; wrap(atan2(dy, dx) - theta) ],  dx = l_x - x, dy = l_y - y
// A sensor mounted off the origin (Mount: its pose in the body frame) is seen through the sensor's
// pose x_s = x_r (+) m: h_m(x_r, l) = h(x_s, l), J_z_pose = J_h_xs J_xs_xr (chain rule).
// Bearings are wrapped into (-pi, pi] wherever an angle is formed.
#pragma once

#include <cmath>

#include "geojcbb/core/math.hpp"

namespace geojcbb {

/// Robot pose in the world frame: world_T_robot.
template <typename T>
struct Pose2 {
  T x{};      ///< [m]
  T y{};      ///< [m]
  T theta{};  ///< [rad], in (-pi, pi]
};

/// Predicted range-bearing of landmark l seen from pose x_r.
/// @param[out] J_z_pose      2x3 Jacobian with respect to (x, y, theta); may be null
/// @param[out] J_z_landmark  2x2 Jacobian with respect to (l_x, l_y); may be null
/// Precondition: the landmark is not at the robot's position (range > 0); the caller gates on that.
template <typename T>
Vec2<T> observe(const Pose2<T>& x_r, const Vec2<T>& l, Mat23<T>* J_z_pose = nullptr, Mat2<T>* J_z_landmark = nullptr) {
  const T dx = l.x() - x_r.x;
  const T dy = l.y() - x_r.y;
  const T q = dx * dx + dy * dy;
  const T r = std::sqrt(q);
  Vec2<T> z(r, wrap_angle(fmath::atan2(dy, dx) - x_r.theta));
  if (J_z_landmark != nullptr || J_z_pose != nullptr) {
    Mat2<T> J_l;
    J_l << dx / r, dy / r,  //
        -dy / q, dx / q;
    if (J_z_landmark != nullptr) *J_z_landmark = J_l;
    if (J_z_pose != nullptr) {
      J_z_pose->template leftCols<2>() = -J_l;
      J_z_pose->col(2) = Vec2<T>(T(0), T(-1));
    }
  }
  return z;
}

/// Innovation z - h of a range-bearing measurement, the bearing wrapped into (-pi, pi]. Shared by
/// the gate (individual compatibility) and the filter's update, so it lives below both.
template <typename T>
Vec2<T> innovation(const Vec2<T>& z, const Vec2<T>& h) {
  return Vec2<T>(z.x() - h.x(), wrap_angle(z.y() - h.y()));
}

/// Landmark position from pose x_r and measurement z = (range, bearing): the inverse model used to
/// initialise a new feature.
/// @param[out] J_l_pose  2x3 Jacobian with respect to (x, y, theta); may be null
/// @param[out] J_l_z     2x2 Jacobian with respect to (range, bearing); may be null
template <typename T>
Vec2<T> inverse_observe(const Pose2<T>& x_r, const Vec2<T>& z, Mat23<T>* J_l_pose = nullptr, Mat2<T>* J_l_z = nullptr) {
  const T a = x_r.theta + z.y();
  const T c = fmath::cos(a);
  const T s = fmath::sin(a);
  Vec2<T> l(x_r.x + z.x() * c, x_r.y + z.x() * s);
  if (J_l_pose != nullptr) {
    *J_l_pose << T(1), T(0), -z.x() * s,  //
        T(0), T(1), z.x() * c;
  }
  if (J_l_z != nullptr) {
    *J_l_z << c, -z.x() * s,  //
        s, z.x() * c;
  }
  return l;
}

/// Where the sensor sits on the robot: its pose in the body frame (x forward, y left, theta from
/// the robot's x axis). All zero: at the origin, the model above exactly.
template <typename T>
struct Mount {
  T x{};      ///< [m]
  T y{};      ///< [m]
  T theta{};  ///< [rad]
  bool at_origin() const { return x == T(0) && y == T(0) && theta == T(0); }
};

/// The sensor's pose in the world, x_r (+) m.
/// @param[out] J_s_pose  3x3 Jacobian with respect to (x, y, theta) of the robot; may be null
template <typename T>
Pose2<T> sensor_pose(const Pose2<T>& x_r, const Mount<T>& m, Mat3<T>* J_s_pose = nullptr) {
  const T c = fmath::cos(x_r.theta);
  const T s = fmath::sin(x_r.theta);
  const Pose2<T> x_s{x_r.x + c * m.x - s * m.y, x_r.y + s * m.x + c * m.y, wrap_angle(x_r.theta + m.theta)};
  if (J_s_pose != nullptr) {
    *J_s_pose << T(1), T(0), -s * m.x - c * m.y,  //
        T(0), T(1), c * m.x - s * m.y,            //
        T(0), T(0), T(1);
  }
  return x_s;
}

/// observe() through a mount: the landmark seen from the sensor's pose; the pose Jacobian with
/// respect to the robot's pose. At the origin it is observe() itself (the same operations). Always
/// inline: a wrapper, not a frame of its own in the device's call chains.
template <typename T>
[[gnu::always_inline]] inline Vec2<T> observe(const Pose2<T>& x_r, const Mount<T>& m, const Vec2<T>& l,
                                              Mat23<T>* J_z_pose = nullptr, Mat2<T>* J_z_landmark = nullptr) {
  if (m.at_origin()) return observe(x_r, l, J_z_pose, J_z_landmark);
  Mat3<T> J_s;
  const Pose2<T> x_s = sensor_pose(x_r, m, J_z_pose != nullptr ? &J_s : nullptr);
  Vec2<T> z = observe(x_s, l, J_z_pose, J_z_landmark);
  if (J_z_pose != nullptr) *J_z_pose = (*J_z_pose * J_s).eval();
  return z;
}

/// inverse_observe() through a mount: the landmark from the robot's pose and the sensor's
/// measurement; the pose Jacobian with respect to the robot's pose. At the origin it is
/// inverse_observe() itself.
template <typename T>
[[gnu::always_inline]] inline Vec2<T> inverse_observe(const Pose2<T>& x_r, const Mount<T>& m, const Vec2<T>& z,
                                                      Mat23<T>* J_l_pose = nullptr, Mat2<T>* J_l_z = nullptr) {
  if (m.at_origin()) return inverse_observe(x_r, z, J_l_pose, J_l_z);
  Mat3<T> J_s;
  const Pose2<T> x_s = sensor_pose(x_r, m, J_l_pose != nullptr ? &J_s : nullptr);
  Vec2<T> l = inverse_observe(x_s, z, J_l_pose, J_l_z);
  if (J_l_pose != nullptr) *J_l_pose = (*J_l_pose * J_s).eval();
  return l;
}

}  // namespace geojcbb
