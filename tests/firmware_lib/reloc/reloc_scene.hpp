// tests: the relocaliser's and the loop check's constructed scene: a random map and noise-free
// observations of it from a pose.
#pragma once

#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/node/slam_step.hpp"

namespace geojcbb::test {

/// 60 landmarks at least 3 m apart in a 50 m square (a fixed seed).
inline std::vector<Eigen::Vector2d> reloc_map() {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-25, 25);
  std::vector<Eigen::Vector2d> map;
  while (map.size() < 60) {
    const Eigen::Vector2d p(u(rng), u(rng));
    bool ok = true;
    for (const auto& q : map) ok = ok && (p - q).norm() >= 3;
    if (ok) map.push_back(p);
  }
  return map;
}

/// The point p seen from x, appended to obs (noise-free; R for 0.1 m and 1 degree) when it is within
/// 20 m ahead of x (1.5 rad either side) and obs has room, or always with `anywhere`.
template <typename T, class B>
void observe_point(const Pose2<double>& x, const Eigen::Vector2d& p, Observations<T, B>& obs, bool anywhere = false) {
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  const double dx = p.x() - x.x, dy = p.y() - x.y;
  const double r = std::hypot(dx, dy), b = wrap_angle(std::atan2(dy, dx) - x.theta);
  if (!anywhere && (r > 20 || std::abs(b) > 1.5 || obs.count >= B::kMaxObservations)) return;
  REQUIRE(obs.push(Vec2<T>(T(r), T(b)), R) == Status::kOk);
}

/// The landmarks within 20 m ahead of `x` (1.5 rad either side) as observations (observe_point).
template <typename T, class B>
void observe_from(const std::vector<Eigen::Vector2d>& map, const Pose2<double>& x, Observations<T, B>& obs) {
  obs.clear();
  for (const auto& l : map) observe_point(x, l, obs);
}

/// A SLAM step, its scan and its result (heap-held by the tests: the step is large).
template <typename T, class B>
struct RelocRig {
  node::SlamStep<T, B> step;
  Observations<T, B> obs;
  node::StepResult<T, B> out;
};

/// The scene's step settings: JCBB, the sensor of observe_from, a known map (nothing added, every
/// landmark confirmed); the caller switches the relocaliser or the loop check in.
template <typename T>
StepSettings<T> reloc_settings() {
  StepSettings<T> s;
  s.strategy = Strategy::kJcbb;
  s.local_radius_m = T(25);
  s.max_range_m = T(20);
  s.half_fov_rad = T(1.5);
  s.augment = false;  // known landmarks are confirmed (ekf::LandmarkPolicy)
  return s;
}

/// A step configured with `s`, at pose x0 with covariance P0, the landmarks of `map` known (1e-4 m^2;
/// `surveyed`: SlamStep::add_known_landmark's flag).
template <typename T, class B>
std::unique_ptr<RelocRig<T, B>> make_known_map_rig(const std::vector<Eigen::Vector2d>& map, const StepSettings<T>& s,
                                                   const Pose2<double>& x0, const Mat3<T>& P0, bool surveyed = false) {
  auto rig = std::make_unique<RelocRig<T, B>>();
  REQUIRE(rig->step.configure(s) == Status::kOk);
  REQUIRE(rig->step.reset(Pose2<T>{T(x0.x), T(x0.y), T(x0.theta)}, P0) == Status::kOk);
  for (const auto& l : map) {
    FeatureId id = -1;
    REQUIRE(rig->step.add_known_landmark(l.cast<T>(), Mat2<T>::Identity() * T(1e-4), id, surveyed) == Status::kOk);
  }
  return rig;
}

/// An association override (node::AssociationOverride) that answers with one observation too many:
/// step() must refuse it with nothing changed.
template <typename T, class B>
Status miscounted_association(void*, const Observations<T, B>& obs, const Prediction<T, B>&, const node::MapView<T, B>&,
                              Association<T, B>& out) {
  out.count = obs.count + 1;
  return Status::kOk;
}

/// Distance from the step's position estimate to x's [m].
template <typename T, class B>
double position_error(const node::SlamStep<T, B>& s, const Pose2<double>& x) {
  return std::hypot(double(s.slam().pose().x) - x.x, double(s.slam().pose().y) - x.y);
}

}  // namespace geojcbb::test
