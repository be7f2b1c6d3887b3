// node/stages/augment.hpp alone, over an association built by hand: each observation's outcome (paired,
// unmatched, a mover's, dropped inside the augmentation gate or with augmentation off, a new landmark),
// and a full map (turned away, or room made beyond the local region when evict_when_full allows).
// Nothing here can fail, so there is no bad input to refuse; it allocates nothing.
#include <doctest/doctest.h>

#include <limits>
#include <memory>
#include <vector>

#include "firmware_lib/node/stage_rig.hpp"
#include "geojcbb/node/stages/augment.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {

using B = DefaultBounds;
/// Six observations at most, ten landmarks: a map that fills.
using Tiny = Bounds<6, 8, 3, 300, 10>;

/// One observation per outcome: 0 paired with `paired`, 1 left unmatched, 2 a mover's, 3 unpaired
/// inside the gate, 4 unpaired beyond it (nothing compatible).
template <typename T, class Bd>
void one_of_each(FeatureId paired, Observations<T, Bd>& obs, Association<T, Bd>& assoc) {
  const Mat2<T> R = Vec2<T>(T(0.01), T(3e-4)).asDiagonal();
  obs.clear();
  for (int i = 0; i < 5; ++i) REQUIRE(obs.push(Vec2<T>(T(3 + i), T(0.1) * T(i)), R) == Status::kOk);
  const T inf = std::numeric_limits<T>::infinity();
  assoc = Association<T, Bd>{};
  assoc.count = 5;
  assoc.feature = {};
  assoc.candidate.fill(-1);
  assoc.d2.fill(inf);
  assoc.feature[0] = paired;
  assoc.d2[0] = T(1.5);
  assoc.pairings = 1;
  assoc.feature[1] = kUnmatched;
  assoc.d2[1] = T(2);
  assoc.feature[2] = node::kMoverFeature;
  assoc.feature[3] = kNewFeature;
  assoc.d2[3] = T(4);  // inside the gate below: too close to a landmark to be a new one
  assoc.feature[4] = kNewFeature;
}

/// A map of one landmark and a scan of one observation per outcome, paired with it.
template <typename T>
struct AugmentRig {
  std::vector<FeatureId> ids;
  std::unique_ptr<ekf::Slam<T, B>> slam = test::slam_with<T, B>(Pose2<T>{}, {Vec2<T>(T(3), T(0))}, ids);
  Observations<T, B> obs;
  std::unique_ptr<Association<T, B>> assoc = std::make_unique<Association<T, B>>();
  AssociationConfig<T, B> cfg;
  std::unique_ptr<node::StepResult<T, B>> out = std::make_unique<node::StepResult<T, B>>();
  int added = 0;
  AugmentRig() { one_of_each(ids[0], obs, *assoc); }
  /// augment_unpaired with the gate at 9. @return the landmarks evicted.
  int run() { return node::augment_unpaired(obs, *assoc, cfg, T(9), *slam, *out, added); }
};

}  // namespace

TEST_CASE_TEMPLATE("augment: each observation's outcome, one new landmark", T, float, double) {
  AugmentRig<T> r;
  auto& slam = r.slam;
  auto& out = r.out;
  const auto& ids = r.ids;
  int evicted = -1;
  const FeatureId next = slam->next_id();
  const std::uint64_t allocations = test::allocations_during([&] { evicted = r.run(); });
  CHECK(allocations == 0);
  CHECK(evicted == 0);
  CHECK(r.added == 1);
  REQUIRE(out->count == 5);
  CHECK(out->outcome[0] == node::Outcome::kPaired);
  CHECK(out->feature[0] == ids[0]);
  CHECK(out->d2[0] == T(1.5));
  CHECK(out->outcome[1] == node::Outcome::kUnmatched);
  CHECK(out->feature[1] == -1);
  CHECK(out->outcome[2] == node::Outcome::kMover);
  CHECK(out->outcome[3] == node::Outcome::kNewDropped);
  CHECK(out->outcome[4] == node::Outcome::kNewLandmark);
  CHECK(out->feature[4] == next);
  CHECK(slam->landmarks() == 2);
  // The new landmark is where observation 4 puts it: range 7 m, bearing 0.4 rad from the origin.
  const Vec2<T> l = slam->landmark(slam->index_of(next));
  CHECK(l.x() == doctest::Approx(7 * std::cos(0.4)).epsilon(1e-5));
  CHECK(l.y() == doctest::Approx(7 * std::sin(0.4)).epsilon(1e-5));
}

TEST_CASE_TEMPLATE("augment: augmentation off maps nothing", T, float, double) {
  AugmentRig<T> r;
  r.cfg.augment = false;
  const auto before = test::bytes_of(*r.slam);
  CHECK(r.run() == 0);
  CHECK(r.added == 0);
  CHECK(r.out->outcome[4] == node::Outcome::kNewDropped);
  CHECK(test::bytes_of(*r.slam) == before);
}

TEST_CASE_TEMPLATE("augment: a full map turns a new landmark away, or evicts one beyond the region", T, float, double) {
  std::vector<FeatureId> ids;
  // Ten landmarks (the capacity): nine near the robot, one 50 m away (beyond r + d).
  auto slam = test::slam_with<T, Tiny>(
      Pose2<T>{},
      {Vec2<T>(T(2), T(0)), Vec2<T>(T(3), T(1)), Vec2<T>(T(4), T(-1)), Vec2<T>(T(2), T(2)), Vec2<T>(T(3), T(-2)),
       Vec2<T>(T(5), T(0)), Vec2<T>(T(1), T(3)), Vec2<T>(T(1), T(-3)), Vec2<T>(T(6), T(1)), Vec2<T>(T(50), T(0))},
      ids);
  REQUIRE(slam->landmarks() == Tiny::kMaxLandmarks);
  Observations<T, Tiny> obs;
  Association<T, Tiny> assoc;
  one_of_each(ids[0], obs, assoc);
  AssociationConfig<T, Tiny> cfg;
  cfg.local_radius_m = T(12);
  node::StepResult<T, Tiny> out;
  int added = 0;
  const auto before = test::bytes_of(*slam);
  CHECK(node::augment_unpaired(obs, assoc, cfg, T(9), *slam, out, added) == 0);
  CHECK(out.outcome[4] == node::Outcome::kNotAugmented);
  CHECK(out.feature[4] == -1);
  CHECK(added == 0);
  CHECK(test::bytes_of(*slam) == before);  // turned away: the map as it was

  cfg.evict_when_full = true;
  const FeatureId far = ids[9];
  CHECK(node::augment_unpaired(obs, assoc, cfg, T(9), *slam, out, added) == 1);
  CHECK(out.outcome[4] == node::Outcome::kNewLandmark);
  CHECK(added == 1);
  CHECK(slam->landmarks() == Tiny::kMaxLandmarks);
  CHECK(slam->index_of(far) < 0);      // the landmark beyond the region made room
  CHECK(slam->index_of(ids[0]) >= 0);  // the paired one stays
}
