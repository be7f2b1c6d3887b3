// node/stages/map_seed.hpp alone, over seeds built by hand: a seed far from every landmark becomes a
// confirmed landmark (its existence capped), one compatible with a landmark the map holds is refused
// as a duplicate (kUnmatched, with its d2), one beyond the room left is turned away (kNotAugmented);
// bad input (a count out of range, a non-finite or indefinite seed, a limit over capacity) returns its
// status with the map and the answers unchanged.
#include <doctest/doctest.h>

#include <array>
#include <limits>
#include <vector>

#include "firmware_lib/node/stage_rig.hpp"
#include "geojcbb/node/stages/map_seed.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {

using B = DefaultBounds;
constexpr double kGate = 9.21;  // chi-square 2 dof at 0.99

template <typename T>
node::MapSeed<T> seed_at(T x, T y, T exist_nats = T(3)) {
  node::MapSeed<T> s;
  s.l = Vec2<T>(x, y);
  s.P = Mat2<T>::Identity() * T(0.04);
  s.exist_nats = exist_nats;
  return s;
}

}  // namespace

TEST_CASE_TEMPLATE("map seed: a new landmark, a duplicate refused, no room", T, float, double) {
  std::vector<FeatureId> ids;
  auto slam = test::slam_with<T, B>(Pose2<T>{}, {Vec2<T>(T(4), T(0))}, ids);
  // 0: far from the map's landmark (a new one), its existence above the cap; 1: 0.1 m from the map's
  // landmark (the map made it anew); 2: new, but the limit leaves room for one seed only.
  const std::array<node::MapSeed<T>, 3> seeds{seed_at(T(10), T(5), T(100)), seed_at(T(4.1), T(0)),
                                              seed_at(T(-6), T(2))};
  std::array<node::SeedAnswer<T>, 3> answers{};
  const T max_nats = T(6);
  const int limit = slam->landmarks() + 1;
  const FeatureId next = slam->next_id();
  Status st = Status::kInvalidInput;
  const std::uint64_t allocations = test::allocations_during(
      [&] { st = node::seed_map(*slam, T(kGate), max_nats, limit, seeds.data(), 3, answers.data()); });
  CHECK(allocations == 0);
  REQUIRE(st == Status::kOk);

  CHECK(answers[0].outcome == node::Outcome::kNewLandmark);
  CHECK(answers[0].id == next);
  const int j = slam->index_of(next);
  REQUIRE(j >= 0);
  CHECK(slam->confirmed(j));
  CHECK(slam->existence(j) <= max_nats);  // the global map's 100 nats capped at what a landmark can bank
  CHECK(slam->landmark(j).x() == T(10));
  CHECK(slam->landmark(j).y() == T(5));

  CHECK(answers[1].outcome == node::Outcome::kUnmatched);
  CHECK(answers[1].id == kUnmatched);
  // d2 to the map's landmark: 0.1^2 / (0.04 + 0.01).
  CHECK(answers[1].d2 == doctest::Approx(0.01 / 0.05).epsilon(1e-4));

  CHECK(answers[2].outcome == node::Outcome::kNotAugmented);
  CHECK(slam->landmarks() == 2);
}

TEST_CASE_TEMPLATE("map seed: bad input changes nothing", T, float, double) {
  std::vector<FeatureId> ids;
  auto slam = test::slam_with<T, B>(Pose2<T>{}, {Vec2<T>(T(4), T(0))}, ids);
  std::array<node::MapSeed<T>, node::kMaxSeeds + 1> seeds{};
  for (int k = 0; k <= node::kMaxSeeds; ++k) seeds[static_cast<std::size_t>(k)] = seed_at(T(10 + k), T(5));
  std::array<node::SeedAnswer<T>, node::kMaxSeeds + 1> answers{};
  answers[0].d2 = T(-1);  // a marker: an answer is written only by a call that succeeds
  const auto slam_before = test::bytes_of(*slam);
  const int limit = B::kMaxLandmarks - B::kMaxObservations;
  const T gate = T(kGate), nats = T(6);

  CHECK(node::seed_map(*slam, gate, nats, limit, seeds.data(), -1, answers.data()) == Status::kInvalidInput);
  CHECK(node::seed_map(*slam, gate, nats, limit, seeds.data(), node::kMaxSeeds + 1, answers.data()) ==
        Status::kInvalidInput);
  CHECK(node::seed_map(*slam, gate, std::numeric_limits<T>::infinity(), limit, seeds.data(), 1, answers.data()) ==
        Status::kInvalidInput);
  CHECK(node::seed_map(*slam, gate, nats, limit + 1, seeds.data(), 1, answers.data()) == Status::kInvalidInput);

  // A bad seed after a good one: neither is seeded.
  seeds[1].l.x() = std::numeric_limits<T>::quiet_NaN();
  CHECK(node::seed_map(*slam, gate, nats, limit, seeds.data(), 2, answers.data()) == Status::kNonFinite);
  seeds[1] = seed_at(T(11), T(5));
  seeds[1].exist_nats = std::numeric_limits<T>::infinity();
  CHECK(node::seed_map(*slam, gate, nats, limit, seeds.data(), 2, answers.data()) == Status::kNonFinite);
  seeds[1] = seed_at(T(11), T(5));
  seeds[1].P << T(1), T(2), T(2), T(1);  // indefinite
  CHECK(node::seed_map(*slam, gate, nats, limit, seeds.data(), 2, answers.data()) == Status::kNotPositiveDefinite);

  CHECK(test::bytes_of(*slam) == slam_before);
  CHECK(answers[0].d2 == T(-1));
}
