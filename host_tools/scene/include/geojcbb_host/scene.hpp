// host_tools/scene: generated EKF-SLAM-like association problems with ground truth, for tests and
// benchmarks. The joint error is generative: e = A w with w ~ N(0, diag(...)), where w holds a common
// rigid map error (3), an independent robot error (3) and an independent error per landmark (2 each),
// so the state covariance P = A W A^T is exactly the distribution the estimates are drawn from.
// Host code: allocates freely.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/range_bearing.hpp"

namespace geojcbb::host {

struct SceneParams {
  int observations = 10;          ///< M: observations in the scan (real + clutter)
  int landmarks = 20;             ///< N: mapped landmarks, all offered as candidates
  double clutter_fraction = 0.2;  ///< share of the M observations that are clutter
  double max_range_m = 8.0;       ///< the sensor sees landmarks (and clutter) within this range
  /// Landmarks are mapped within this distance of the robot, all around; 0: only within the field
  /// of view and max_range_m (every landmark observable).
  double map_range_m = 0.0;
  double min_range_m = 0.5;
  double max_abs_bearing_rad = 2.6;  ///< field of view; keeps bearings away from +-pi (MRPT)
  double min_separation_m = 0.0;     ///< minimum distance between true landmarks (0: none)
  double sigma_range_m = 0.1;        ///< measurement noise (one R for every observation)
  double sigma_bearing_rad = 0.0175;
  double sigma_pose_xy_m = 0.3;  ///< robot's own error
  double sigma_pose_theta_rad = 0.03;
  double sigma_common_xy_m = 0.2;  ///< rigid error shared by the map and the robot
  double sigma_common_theta_rad = 0.02;
  double sigma_landmark_m = 0.15;  ///< independent error of each landmark
};

struct Scene {
  Pose2<double> true_pose;
  Pose2<double> est_pose;
  std::vector<Eigen::Vector2d> true_landmarks;  ///< N
  std::vector<Eigen::Vector2d> est_landmarks;   ///< N
  Eigen::MatrixXd P;                            ///< (3 + 2N) x (3 + 2N) state covariance
  std::vector<Eigen::Vector2d> z;               ///< M measurements (range, bearing)
  Eigen::Matrix2d R;                            ///< noise of every measurement
  std::vector<int> truth;                       ///< per observation: landmark index, -1 = clutter
  std::vector<Eigen::Vector2d> h;               ///< N predicted measurements from est_pose
  Eigen::MatrixXd C;                            ///< 2N x 2N  H P H^T
};

/// d(state)/d(w) for a small rigid motion w = (dx, dy, dtheta) of the whole state about the world
/// origin: (3 + 2N) x 3, state = (pose, landmarks). The scenes' common map error is A w.
Eigen::MatrixXd rigid_motion_jacobian(const Pose2<double>& pose, const std::vector<Eigen::Vector2d>& landmarks);

/// Generates one scene; deterministic for a seed.
Scene make_scene(const SceneParams& p, std::uint64_t seed);

/// Recomputes s.h and s.C = H P H^T from s.est_pose, s.est_landmarks and s.P (make_scene calls it;
/// a test that moves the estimate calls it again).
void predict_measurements(Scene& s);

/// Copies a scene into the fixed-capacity inputs of the association core.
/// @return false when the scene exceeds the capacity B.
template <typename T, class B>
bool to_inputs(const Scene& s, Observations<T, B>& obs, Prediction<T, B>& pred) {
  const int m = static_cast<int>(s.z.size());
  const int n = static_cast<int>(s.h.size());
  if (m > B::kMaxObservations || n > B::kMaxCandidates) return false;
  obs.count = m;
  for (int i = 0; i < m; ++i) {
    obs.z[i] = s.z[i].cast<T>();
    obs.R[i] = s.R.cast<T>();
  }
  // The scene's C is exactly symmetric (predict_measurements); the packed C holds its lower blocks.
  if (pred.C.assign_dense(s.C) != Status::kOk) return false;
  pred.count = n;
  for (int j = 0; j < n; ++j) {
    pred.id[j] = j;
    pred.h[j] = s.h[j].cast<T>();
  }
  return true;
}

/// Scores a hypothesis (per observation: landmark index or -1) against the scene's truth.
struct Score {
  int tp = 0;  ///< correct pairs
  int fp = 0;  ///< wrong pairs (wrong feature, or clutter paired)
  int fn = 0;  ///< true pairs not made (unpaired or paired wrongly)
  int tn = 0;  ///< clutter left unpaired
  void add(const Score& o) {
    tp += o.tp;
    fp += o.fp;
    fn += o.fn;
    tn += o.tn;
  }
  double precision() const { return tp + fp == 0 ? 1.0 : double(tp) / (tp + fp); }
  double recall() const { return tp + fn == 0 ? 1.0 : double(tp) / (tp + fn); }
  double f1() const {
    const double p = precision(), r = recall();
    return p + r == 0 ? 0.0 : 2 * p * r / (p + r);
  }
};
Score score(const Scene& s, const std::vector<int>& hypothesis);

}  // namespace geojcbb::host
