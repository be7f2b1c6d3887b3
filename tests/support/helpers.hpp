// tests/support: bounds used by the tests and small helpers shared by several test files.
#pragma once

#include <memory>

#include <doctest/doctest.h>

#include "geojcbb/associate.hpp"
#include "geojcbb_host/scene.hpp"

namespace geojcbb::test {

/// Small capacity (exhaustive oracles) and the controller default: tests run over both.
using SmallBounds = Bounds<8, 12, 4, 1000000, 16>;
using HostBounds = Bounds<32, 128, 8, 200000, 128>;

template <typename T, class B>
AssociationConfig<T, B> make_config(SearchMethod search, bool exclusion, bool optimal, double confidence = 0.99) {
  AssociationConfig<T, B> cfg;
  cfg.search = search;
  cfg.mutual_exclusion = exclusion;
  cfg.optimal_criterion = optimal;
  REQUIRE(GateThresholds<T, B::kMaxObservations>::from_confidence(confidence, confidence, cfg.gate) == Status::kOk);
  return cfg;
}

/// The association core's large objects, on the heap for tests (the library never allocates; a
/// test may, outside the measured call).
template <typename T, class B>
struct Problem {
  Observations<T, B> obs;
  Prediction<T, B> pred;
  AssociationWorkspace<T, B> ws;
  Association<T, B> out;
};
template <typename T, class B>
std::unique_ptr<Problem<T, B>> make_problem() {
  return std::make_unique<Problem<T, B>>();
}

/// A generated scene loaded into a Problem's inputs (the scene must fit the bounds).
template <typename T, class B>
std::unique_ptr<Problem<T, B>> scene_problem(const host::SceneParams& params, std::uint64_t seed) {
  auto p = make_problem<T, B>();
  REQUIRE(host::to_inputs(host::make_scene(params, seed), p->obs, p->pred));
  return p;
}

}  // namespace geojcbb::test
