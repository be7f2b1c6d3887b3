// tests: the relocaliser's and the loop check's constructed scene: a random map and noise-free
// observations of it from a pose.
#pragma once

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/range_bearing.hpp"

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

/// The landmarks within 20 m ahead of `x` (1.5 rad either side) as observations (noise-free; R for
/// 0.1 m and 1 degree).
template <typename T, class B>
void observe_from(const std::vector<Eigen::Vector2d>& map, const Pose2<double>& x, Observations<T, B>& obs) {
  obs.clear();
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  for (const auto& l : map) {
    const double dx = l.x() - x.x, dy = l.y() - x.y;
    const double r = std::hypot(dx, dy), b = wrap_angle(std::atan2(dy, dx) - x.theta);
    if (r > 20 || std::abs(b) > 1.5 || obs.count >= B::kMaxObservations) continue;
    REQUIRE(obs.push(Vec2<T>(T(r), T(b)), R) == Status::kOk);
  }
}

}  // namespace geojcbb::test
