// node/stages/map_view.hpp alone: the map as the stages read it (slots and ids, means and 2x2 blocks
// as the filter holds them, confirmed false for no slot), the alignment scratch's slots in push order,
// and the only edits of an association after associate() (pair, unpair, recount), which keep
// `pairings` true. Its calls return no status (the view reads a filter that is valid).
#include <doctest/doctest.h>

#include <memory>
#include <vector>

#include "firmware_lib/node/stage_rig.hpp"
#include "geojcbb/node/stages/map_view.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {
using B = DefaultBounds;
}  // namespace

TEST_CASE_TEMPLATE("map view: the filter's landmarks by slot and by id", T, float, double) {
  std::vector<FeatureId> ids;
  auto slam =
      test::slam_with<T, B>(Pose2<T>{T(1), T(2), T(0.5)}, {Vec2<T>(T(4), T(1)), Vec2<T>(T(-3), T(2))}, ids, T(0.2));
  const ekf::LandmarkPolicy policy;
  const node::MapView<T, B> map(*slam, policy);
  CHECK(map.size() == 2);
  for (int k = 0; k < 2; ++k) {
    CAPTURE(k);
    CHECK(map.id(k) == ids[static_cast<std::size_t>(k)]);
    CHECK(map.slot_of(ids[static_cast<std::size_t>(k)]) == k);
    CHECK(map.mean(k) == slam->landmark(k));
    CHECK(map.cov(k)(0, 0) == doctest::Approx(0.04));
    CHECK(map.cov(k)(0, 1) == T(0));
    CHECK(map.position_var(k) == doctest::Approx(0.08));
    CHECK(map.confirmed(k));  // known landmarks start confirmed
  }
  CHECK(map.slot_of(kNewFeature) == -1);
  CHECK(map.slot_of(kUnmatched) == -1);
  CHECK(map.slot_of(map.next_id()) == -1);
  CHECK_FALSE(map.confirmed(-1));
  CHECK(map.pose().x == T(1));
  CHECK(map.pose_cov(2, 2) == doctest::Approx(0.001));
}

TEST_CASE_TEMPLATE("map view: the alignment scratch keeps each pushed landmark's slot", T, float, double) {
  std::vector<FeatureId> ids;
  auto slam = test::slam_with<T, B>(Pose2<T>{}, {Vec2<T>(T(4), T(1)), Vec2<T>(T(-3), T(2)), Vec2<T>(T(0), T(6))}, ids);
  const ekf::LandmarkPolicy policy;
  const node::MapView<T, B> map(*slam, policy);
  auto scratch = std::make_unique<node::AlignScratch<T, B>>();
  scratch->clear();
  const std::uint64_t allocations = test::allocations_during([&] {
    REQUIRE(scratch->push(map, 2) == Status::kOk);
    REQUIRE(scratch->push(map, 0) == Status::kOk);
  });
  CHECK(allocations == 0);
  CHECK(scratch->ws.n == 2);
  CHECK(scratch->slot_at(0) == 2);
  CHECK(scratch->slot_at(1) == 0);
  scratch->clear();
  CHECK(scratch->ws.n == 0);
}

TEST_CASE_TEMPLATE("map view: pair, unpair and recount keep pairings true", T, float, double) {
  auto pred = std::make_unique<Prediction<T, B>>();
  pred->count = 2;
  pred->id[0] = 10;
  pred->id[1] = 11;
  Association<T, B> a;
  a.count = 3;
  a.feature = {};
  a.feature[0] = kNewFeature;
  a.feature[1] = 10;
  a.feature[2] = kUnmatched;
  a.candidate.fill(-1);
  a.candidate[1] = 0;
  a.pairings = 1;

  node::pair(a, *pred, 0, FeatureId(11), T(2.5));  // an unpaired observation paired
  CHECK(a.pairings == 2);
  CHECK(a.feature[0] == 11);
  CHECK(a.candidate[0] == 1);
  CHECK(a.d2[0] == T(2.5));
  node::pair(a, *pred, 1, FeatureId(42), T(1));  // re-paired with a feature that is not a candidate
  CHECK(a.pairings == 2);
  CHECK(a.candidate[1] == -1);
  node::unpair(a, 1);
  CHECK(a.pairings == 1);
  CHECK(a.feature[1] == kUnmatched);
  node::unpair(a, 2);  // already unpaired: the count stays
  CHECK(a.pairings == 1);
  a.pairings = 7;  // made by other means: recounted
  node::recount(a);
  CHECK(a.pairings == 1);
}
