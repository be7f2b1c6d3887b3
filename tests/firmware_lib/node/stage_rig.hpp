// tests: inputs for the SLAM step's stages built by hand (not through SlamStep::step): a filter with
// landmarks placed where a test wants them, and its state as bytes to prove "nothing changed".
#pragma once

#include <doctest/doctest.h>

#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <memory>
#include <vector>

#include "geojcbb/ekf/slam.hpp"

namespace geojcbb::test {

/// A filter at `pose` (covariance diag(0.01, 0.01, 0.001)) with known landmarks at `at` (each with
/// covariance sigma_m^2 I, confirmed), their ids in `ids`.
template <typename T, class B>
std::unique_ptr<ekf::Slam<T, B>> slam_with(const Pose2<T>& pose, std::initializer_list<Vec2<T>> at,
                                           std::vector<FeatureId>& ids, T sigma_m = T(0.1)) {
  auto s = std::make_unique<ekf::Slam<T, B>>();
  REQUIRE(s->reset(pose, Vec3<T>(T(0.01), T(0.01), T(0.001)).asDiagonal()) == Status::kOk);
  ids.clear();
  for (const Vec2<T>& l : at) {
    FeatureId id = -1;
    REQUIRE(s->add_known_landmark(l, Mat2<T>::Identity() * (sigma_m * sigma_m), id) == Status::kOk);
    ids.push_back(id);
  }
  return s;
}

/// An object's bytes (padding included), to compare before and after a call that must change nothing.
template <class O>
std::vector<std::uint8_t> bytes_of(const O& o) {
  std::vector<std::uint8_t> b(sizeof(O));
  std::memcpy(b.data(), static_cast<const void*>(&o), sizeof(O));
  return b;
}

}  // namespace geojcbb::test
