// core: the range-bearing sensor model z = h(x_r, l) of a 2D laser at the robot's origin, its inverse
// (a landmark from a pose and a measurement) and their analytic Jacobians, named J_out_in.
//   h(x_r, l) = [ sqrt(dx^2 + dy^2) ; wrap(atan2(dy, dx) - theta) ],  dx = l_x - x, dy = l_y - y
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

}  // namespace geojcbb
