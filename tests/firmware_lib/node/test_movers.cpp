// node/stages/movers.hpp alone, over scans built by hand: an observation whose landmark failed the
// motion test begins a track (start: marked a mover's, its pairing taken back); the track then takes
// the nearest observation in its gate as the thing moves, and leaves the others alone; unseen for
// kForgetScans scans it is dropped; a thing that stands still is given back to the map (kStillNats).
// Its calls return no status (the observations were validated by the association); none allocates.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "firmware_lib/node/stage_rig.hpp"
#include "geojcbb/node/stages/movers.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {

using B = DefaultBounds;

/// A robot at the origin with one landmark, and scans of points given in the world frame.
template <typename T>
struct MoverRig {
  std::vector<FeatureId> ids;
  std::unique_ptr<ekf::Slam<T, B>> slam = test::slam_with<T, B>(Pose2<T>{}, {Vec2<T>(T(6), T(-2))}, ids);
  ekf::LandmarkPolicy policy;
  node::MapView<T, B> map{*slam, policy};
  Observations<T, B> obs;
  std::unique_ptr<Association<T, B>> assoc = std::make_unique<Association<T, B>>();
  node::Movers<T, B> movers;

  MoverRig() { movers.reset(); }
  /// A scan of these world points (range 0.05 m, bearing 0.01 rad sigmas), each unpaired but the
  /// first, paired with the landmark when `paired`.
  void scan(std::initializer_list<Vec2<T>> points, bool paired) {
    obs.clear();
    const Mat2<T> R = Vec2<T>(T(0.0025), T(1e-4)).asDiagonal();
    for (const Vec2<T>& p : points) REQUIRE(obs.push(Vec2<T>(p.norm(), std::atan2(p.y(), p.x())), R) == Status::kOk);
    *assoc = Association<T, B>{};
    assoc->count = obs.count;
    assoc->feature.fill(kNewFeature);
    assoc->candidate.fill(-1);
    assoc->pairings = 0;
    if (paired) {
      assoc->feature[0] = ids[0];
      assoc->candidate[0] = 0;
      assoc->pairings = 1;
    }
  }
};

constexpr double kGate = 9.21;

}  // namespace

TEST_CASE_TEMPLATE("movers: a track begins, follows its mover, and leaves the rest alone", T, float, double) {
  MoverRig<T> r;
  r.scan({Vec2<T>(T(4), T(1))}, true);
  r.movers.start(r.obs, r.map, 0, *r.assoc);  // its landmark failed the motion test
  CHECK(r.movers.tracks() == 1);
  CHECK(r.movers.caught() == 1);
  CHECK(r.assoc->feature[0] == node::kMoverFeature);
  CHECK(r.assoc->pairings == 0);
  CHECK(r.movers.track(0).x() == doctest::Approx(4).epsilon(1e-4));
  CHECK(r.movers.track(0).y() == doctest::Approx(1).epsilon(1e-4));

  // The next scan: the mover 0.2 m on, and a landmark elsewhere.
  r.scan({Vec2<T>(T(9), T(3)), Vec2<T>(T(4.2), T(1))}, false);
  int taken = -1;
  const std::uint64_t allocations =
      test::allocations_during([&] { taken = r.movers.take(r.obs, r.map, T(kGate), *r.assoc); });
  CHECK(allocations == 0);
  CHECK(taken == 1);
  CHECK(r.assoc->feature[0] == kNewFeature);
  CHECK(r.assoc->feature[1] == node::kMoverFeature);
  CHECK(r.movers.track(0).x() > T(4.05));  // the track moved towards its sighting
}

TEST_CASE_TEMPLATE("movers: a track unseen for kForgetScans scans is dropped", T, float, double) {
  MoverRig<T> r;
  r.scan({Vec2<T>(T(4), T(1))}, true);
  r.movers.start(r.obs, r.map, 0, *r.assoc);
  r.scan({Vec2<T>(T(-5), T(-5))}, false);  // nothing near the track
  for (int s = 1; s < node::Movers<T, B>::kForgetScans; ++s) {
    CHECK(r.movers.take(r.obs, r.map, T(kGate), *r.assoc) == 0);
  }
  CHECK(r.movers.tracks() == 1);
  CHECK(r.movers.take(r.obs, r.map, T(kGate), *r.assoc) == 0);
  CHECK(r.movers.tracks() == 0);
  CHECK(r.assoc->feature[0] == kNewFeature);
  CHECK(r.movers.caught() == 1);  // caught stays counted
}

TEST_CASE_TEMPLATE("movers: a thing that stands still is given back to the map", T, float, double) {
  MoverRig<T> r;
  r.scan({Vec2<T>(T(4), T(1))}, true);
  r.movers.start(r.obs, r.map, 0, *r.assoc);
  // The same point scan after scan: standing still explains it better than the walk, by kStillNats in
  // a bounded number of sightings; from then on its observation is free (not a mover's).
  int scans = 0;
  bool given_back = false;
  for (; scans < node::Movers<T, B>::kForgetScans && !given_back; ++scans) {
    r.scan({Vec2<T>(T(4), T(1))}, false);
    given_back = r.movers.take(r.obs, r.map, T(kGate), *r.assoc) == 0;
  }
  CHECK(given_back);
  CHECK(scans > 1);
  CHECK(r.assoc->feature[0] == kNewFeature);
  r.scan({Vec2<T>(T(4), T(1))}, false);
  CHECK(r.movers.take(r.obs, r.map, T(kGate), *r.assoc) == 0);
  CHECK(r.movers.tracks() == 0);
}
