// tests/support: scenes for the consistency stage (consistency/): a rigid motion of a scene's world,
// and an independent, world-frame computation of the pairwise distance test from the state
// covariance P (not from C = H P H^T), the oracle of consistency/pairwise.hpp.
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb_host/scene.hpp"

namespace geojcbb::test {

/// Scene parameters of the consistency tests: 20 % clutter, 10 m range, landmarks >= 1 m apart, and
/// the given pose uncertainty (large values: loop closure, relocalisation).
inline host::SceneParams consistency_scene_params(int m, int n, double sigma_pose_xy_m, double sigma_pose_theta_rad) {
  host::SceneParams p;
  p.observations = m;
  p.landmarks = n;
  p.clutter_fraction = 0.2;
  p.max_range_m = 10;
  p.min_separation_m = 1.0;
  p.sigma_pose_xy_m = sigma_pose_xy_m;
  p.sigma_pose_theta_rad = sigma_pose_theta_rad;
  return p;
}

/// The scene with its world rotated by phi and translated by t (poses, landmarks, P); h and C
/// recomputed. The measurements z are relative to the robot and stay as they are.
inline host::Scene rigidly_moved(const host::Scene& s, double phi, const Eigen::Vector2d& t) {
  Eigen::Matrix2d rot;
  rot << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  auto move = [&](const Pose2<double>& p) {
    const Eigen::Vector2d q = rot * Eigen::Vector2d(p.x, p.y) + t;
    return Pose2<double>{q.x(), q.y(), wrap_angle(p.theta + phi)};
  };
  host::Scene m = s;
  m.true_pose = move(s.true_pose);
  m.est_pose = move(s.est_pose);
  const int n = static_cast<int>(s.est_landmarks.size());
  Eigen::MatrixXd T = Eigen::MatrixXd::Identity(3 + 2 * n, 3 + 2 * n);
  T.block<2, 2>(0, 0) = rot;
  for (int j = 0; j < n; ++j) {
    m.true_landmarks[j] = rot * s.true_landmarks[j] + t;
    m.est_landmarks[j] = rot * s.est_landmarks[j] + t;
    T.block<2, 2>(3 + 2 * j, 3 + 2 * j) = rot;
  }
  m.P = T * s.P * T.transpose();
  host::predict_measurements(m);
  return m;
}

/// The distance test of pairings (i, a), (k, b) in the world frame: observed distance and its
/// variance from z and R; predicted distance |l_a - l_b| between the estimated landmarks and its
/// variance g^T (P_aa + P_bb - P_ab - P_ba) g, read from the state covariance.
struct WorldPairStatistic {
  double observed_m = 0, predicted_m = 0, var_observed = 0, var_predicted = 0;
  double d2() const {
    const double e = observed_m - predicted_m;
    return e * e / (var_observed + var_predicted);
  }
};

inline WorldPairStatistic world_pair_statistic(const host::Scene& s, int i, int a, int k, int b) {
  auto point = [](const Eigen::Vector2d& z, Eigen::Matrix2d& J) {
    const double c = std::cos(z.y()), sn = std::sin(z.y());
    J << c, -z.x() * sn, sn, z.x() * c;
    return Eigen::Vector2d(z.x() * c, z.x() * sn);
  };
  Eigen::Matrix2d Ji, Jk;
  const Eigen::Vector2d u = point(s.z[i], Ji) - point(s.z[k], Jk);
  const Eigen::Matrix2d Su = Ji * s.R * Ji.transpose() + Jk * s.R * Jk.transpose();
  const Eigen::Vector2d v = s.est_landmarks[a] - s.est_landmarks[b];
  const int ra = 3 + 2 * a, rb = 3 + 2 * b;
  const Eigen::Matrix2d Sv =
      s.P.block<2, 2>(ra, ra) + s.P.block<2, 2>(rb, rb) - s.P.block<2, 2>(ra, rb) - s.P.block<2, 2>(rb, ra);
  WorldPairStatistic w;
  w.observed_m = u.norm();
  w.predicted_m = v.norm();
  const Eigen::Vector2d gu = u / w.observed_m, gv = v / w.predicted_m;
  w.var_observed = gu.dot(Su * gu);
  w.var_predicted = gv.dot(Sv * gv);
  return w;
}

/// A constructed relocalisation: seven mapped landmarks with distinct pairwise distances, the robot
/// at the origin, its estimate 2.5 m and 0.8 rad (46 deg) off (with a covariance that admits it),
/// one clutter return. Measurements carry fixed small errors.
inline host::Scene wrong_pose_scene() {
  host::Scene s;
  s.true_pose = {0.0, 0.0, 0.0};
  s.est_pose = {2.0, -1.5, 0.8};
  s.true_landmarks = {{8.2, 0.8}, {10.5, -0.8}, {7.1, -2.5}, {10.3, 5.3}, {3.7, 3.9}, {2.4, 5.6}, {9.4, -3.8}};
  const double offsets[7][2] = {{0.03, -0.02}, {-0.04, 0.01}, {0.02, 0.05}, {-0.01, -0.03},
                                {0.05, 0.02},  {-0.03, 0.04}, {0.01, -0.05}};
  const int n = static_cast<int>(s.true_landmarks.size());
  for (int j = 0; j < n; ++j) {
    s.est_landmarks.push_back(s.true_landmarks[j] + Eigen::Vector2d(offsets[j][0], offsets[j][1]));
  }
  s.P = Eigen::MatrixXd::Zero(3 + 2 * n, 3 + 2 * n);
  s.P.topLeftCorner<3, 3>() = Eigen::Vector3d(2.5 * 2.5, 2.5 * 2.5, 1.0).asDiagonal();
  s.P.bottomRightCorner(2 * n, 2 * n).diagonal().setConstant(0.05 * 0.05);
  host::predict_measurements(s);
  s.R = Eigen::Vector2d(0.05 * 0.05, 0.01 * 0.01).asDiagonal();
  // Observations in a scrambled order; the clutter return third.
  const int order[8] = {4, 0, -1, 6, 2, 5, 1, 3};
  const double noise[8][2] = {{0.02, -0.004},  {-0.03, 0.006}, {0, 0},         {0.04, 0.002},
                              {-0.01, -0.008}, {0.03, 0.005},  {-0.02, 0.003}, {0.01, -0.006}};
  for (int q = 0; q < 8; ++q) {
    s.truth.push_back(order[q]);
    Vec2<double> z =
        order[q] >= 0 ? observe(s.true_pose, Vec2<double>(s.true_landmarks[order[q]])) : Vec2<double>(6.0, -0.3);
    z.x() += noise[q][0];
    z.y() += noise[q][1];
    s.z.push_back(z);
  }
  return s;
}

}  // namespace geojcbb::test
