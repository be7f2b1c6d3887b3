#include "geojcbb_host/scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace geojcbb::host {

Eigen::MatrixXd rigid_motion_jacobian(const Pose2<double>& pose, const std::vector<Eigen::Vector2d>& landmarks) {
  const int n = static_cast<int>(landmarks.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 + 2 * n, 3);
  auto rigid = [&](int row, const Eigen::Vector2d& at) {  // small rotation about the origin
    A(row, 0) = 1;
    A(row + 1, 1) = 1;
    A(row, 2) = -at.y();
    A(row + 1, 2) = at.x();
  };
  rigid(0, Eigen::Vector2d(pose.x, pose.y));
  A(2, 2) = 1;
  for (int j = 0; j < n; ++j) rigid(3 + 2 * j, landmarks[j]);
  return A;
}

Scene make_scene(const SceneParams& p, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  auto point_in_view = [&](const Pose2<double>& pose) {
    const double r = std::sqrt(p.min_range_m * p.min_range_m +
                               uni(rng) * (p.max_range_m * p.max_range_m - p.min_range_m * p.min_range_m));
    const double b = (2 * uni(rng) - 1) * p.max_abs_bearing_rad;
    return Eigen::Vector2d(pose.x + r * std::cos(pose.theta + b), pose.y + r * std::sin(pose.theta + b));
  };

  Scene s;
  const int n = p.landmarks;
  s.true_pose = {0.0, 0.0, (2 * uni(rng) - 1) * 0.5};
  auto point_in_map = [&](const Pose2<double>& pose) {
    if (p.map_range_m <= 0) return point_in_view(pose);
    const double r = p.map_range_m * std::sqrt(uni(rng));
    const double b = kTwoPi<double> * uni(rng);
    return Eigen::Vector2d(pose.x + r * std::cos(b), pose.y + r * std::sin(b));
  };
  for (int tries = 0; static_cast<int>(s.true_landmarks.size()) < n && tries < 200 * n; ++tries) {
    const Eigen::Vector2d l = point_in_map(s.true_pose);
    bool ok = true;
    for (const auto& o : s.true_landmarks) ok = ok && (o - l).norm() >= p.min_separation_m;
    if (ok) s.true_landmarks.push_back(l);
  }
  while (static_cast<int>(s.true_landmarks.size()) < n) s.true_landmarks.push_back(point_in_map(s.true_pose));

  // e = A w: w = [common rigid (3) | robot (3) | landmark j (2) ...].
  const int dim = 3 + 2 * n;
  const int wdim = 6 + 2 * n;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(dim, wdim);
  Eigen::VectorXd wsig(wdim);
  wsig << p.sigma_common_xy_m, p.sigma_common_xy_m, p.sigma_common_theta_rad, p.sigma_pose_xy_m, p.sigma_pose_xy_m,
      p.sigma_pose_theta_rad, Eigen::VectorXd::Constant(2 * n, p.sigma_landmark_m);
  A.leftCols<3>() = rigid_motion_jacobian(s.true_pose, s.true_landmarks);
  A.block<3, 3>(0, 3).setIdentity();
  for (int j = 0; j < n; ++j) A.block<2, 2>(3 + 2 * j, 6 + 2 * j).setIdentity();
  Eigen::VectorXd w(wdim);
  for (int k = 0; k < wdim; ++k) w[k] = wsig[k] * gauss(rng);
  const Eigen::VectorXd e = A * w;
  s.P = A * wsig.array().square().matrix().asDiagonal() * A.transpose();
  s.est_pose = {s.true_pose.x + e[0], s.true_pose.y + e[1], wrap_angle(s.true_pose.theta + e[2])};
  for (int j = 0; j < n; ++j) s.est_landmarks.push_back(s.true_landmarks[j] + e.segment<2>(3 + 2 * j));

  predict_measurements(s);

  // Observations: distinct landmarks in random order, then clutter; shuffled.
  s.R = Eigen::Vector2d(p.sigma_range_m * p.sigma_range_m, p.sigma_bearing_rad * p.sigma_bearing_rad).asDiagonal();
  const int clutter = static_cast<int>(std::lround(p.clutter_fraction * p.observations));
  std::vector<int> idx;  // landmarks in the sensor's view (all of them when map_range_m is 0)
  for (int j = 0; j < n; ++j) {
    const Vec2<double> z = observe(s.true_pose, Vec2<double>(s.true_landmarks[j]));
    if (p.map_range_m <= 0 ||
        (z.x() >= p.min_range_m && z.x() <= p.max_range_m && std::abs(z.y()) <= p.max_abs_bearing_rad)) {
      idx.push_back(j);
    }
  }
  const int real = std::min(p.observations - clutter, static_cast<int>(idx.size()));
  std::shuffle(idx.begin(), idx.end(), rng);
  for (int k = 0; k < real; ++k) s.truth.push_back(idx[k]);
  while (static_cast<int>(s.truth.size()) < p.observations) s.truth.push_back(-1);
  std::shuffle(s.truth.begin(), s.truth.end(), rng);
  for (int t : s.truth) {
    const Eigen::Vector2d l = t >= 0 ? s.true_landmarks[t] : point_in_view(s.true_pose);
    Vec2<double> z = observe(s.true_pose, Vec2<double>(l));
    if (t >= 0) {
      z.x() += p.sigma_range_m * gauss(rng);
      z.y() = wrap_angle(z.y() + p.sigma_bearing_rad * gauss(rng));
    }
    z.x() = std::max(z.x(), 0.0);
    s.z.push_back(z);
  }
  return s;
}

void predict_measurements(Scene& s) {
  // C = H P H^T, H = [J_z_pose | 0 .. J_z_landmark_j .. 0].
  const int n = static_cast<int>(s.est_landmarks.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2 * n, 3 + 2 * n);
  s.h.clear();
  for (int j = 0; j < n; ++j) {
    Mat23<double> Jp;
    Mat2<double> Jl;
    s.h.push_back(observe(s.est_pose, Vec2<double>(s.est_landmarks[j]), &Jp, &Jl));
    H.block<2, 3>(2 * j, 0) = Jp;
    H.block<2, 2>(2 * j, 3 + 2 * j) = Jl;
  }
  s.C = H * s.P * H.transpose();
  s.C = (0.5 * (s.C + s.C.transpose())).eval();  // eval: the transpose aliases s.C
}

Score score(const Scene& s, const std::vector<int>& hypothesis) {
  Score sc;
  for (std::size_t i = 0; i < s.truth.size(); ++i) {
    const int t = s.truth[i];
    const int h = hypothesis[i];
    if (h >= 0 && h == t) {
      ++sc.tp;
    } else {
      if (h >= 0) ++sc.fp;
      if (t >= 0) ++sc.fn;
      if (t < 0 && h < 0) ++sc.tn;
    }
  }
  return sc;
}

}  // namespace geojcbb::host
