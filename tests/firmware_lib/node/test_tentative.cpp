// node/stages/tentative.hpp alone, over a map and a scan built by hand (a confirmed landmark and a
// tentative one, the association's answer over the confirmed candidates): pair() offers what the
// association made new to the tentative candidates, set_aside() holds their pairs alone in the plan,
// a tentative landmark whose sighting jumped (outside the pairing gate, inside the augmentation gate)
// is a mover that follow() then tracks. Its calls return no status; none allocates.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "firmware_lib/node/stage_rig.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/gate/compatibility.hpp"
#include "geojcbb/node/stages/tentative.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {

using B = DefaultBounds;

/// A confirmed landmark at (5, 0) and a tentative one made from a sighting at range 4, bearing 0.5;
/// the prediction from the origin with the confirmed candidates first.
template <typename T>
struct TentativeRig {
  std::vector<FeatureId> ids;
  std::unique_ptr<ekf::Slam<T, B>> slam = test::slam_with<T, B>(Pose2<T>{}, {Vec2<T>(T(5), T(0))}, ids);
  FeatureId tentative = -1;
  ekf::LandmarkPolicy policy;
  node::MapView<T, B> map{*slam, policy};
  std::unique_ptr<AssociationConfig<T, B>> cfg = std::make_unique<AssociationConfig<T, B>>();
  std::unique_ptr<ekf::SlamWorkspace<T, B>> ws = std::make_unique<ekf::SlamWorkspace<T, B>>();
  std::unique_ptr<Prediction<T, B>> pred = std::make_unique<Prediction<T, B>>();
  Observations<T, B> obs;
  std::unique_ptr<Association<T, B>> assoc = std::make_unique<Association<T, B>>();
  Mat2<T> R = Vec2<T>(T(0.0025), T(1e-4)).asDiagonal();
  node::Tentative<T, B> stage;

  TentativeRig() {
    REQUIRE(slam->augment(Vec2<T>(T(4), T(0.5)), R, tentative) == Status::kOk);
    REQUIRE_FALSE(slam->confirmed(slam->index_of(tentative)));
    REQUIRE(make_strategy(Strategy::kJcbb, StepSettings<T>{}, *cfg) == Status::kOk);
    ekf::LocalMapStats stats;
    REQUIRE(slam->predict_local(T(12), *ws, *pred, stats, true) == Status::kOk);
    REQUIRE(pred->count == 2);
    REQUIRE(pred->id[0] == ids[0]);  // confirmed first
    stage.reset();
  }
  /// A scan: the confirmed landmark seen where it is (the association paired it) and a sighting at
  /// (range, bearing) the association made new.
  void scan(T range, T bearing) {
    obs.clear();
    REQUIRE(obs.push(Vec2<T>(T(5), T(0)), R) == Status::kOk);
    REQUIRE(obs.push(Vec2<T>(range, bearing), R) == Status::kOk);
    *assoc = Association<T, B>{};
    assoc->count = 2;
    assoc->feature[0] = ids[0];
    assoc->candidate[0] = 0;
    assoc->d2[0] = T(0);
    assoc->feature[1] = kNewFeature;
    assoc->candidate[1] = -1;
    assoc->d2[1] = std::numeric_limits<T>::infinity();
    assoc->pairings = 1;
  }
};

}  // namespace

TEST_CASE_TEMPLATE("tentative: a new observation pairs with a tentative landmark, held alone", T, float, double) {
  TentativeRig<T> r;
  r.scan(T(4.02), T(0.505));
  const std::uint64_t allocations =
      test::allocations_during([&] { r.stage.pair(*r.cfg, r.obs, *r.pred, 1, T(1e6), r.map, *r.assoc); });
  CHECK(allocations == 0);
  CHECK(r.assoc->feature[1] == r.tentative);
  CHECK(r.assoc->candidate[1] == 1);
  CHECK(r.assoc->pairings == 2);
  CHECK(r.assoc->d2[1] <= r.cfg->gate.individual);
  CHECK(r.stage.jumped() == 0);
  CHECK(r.stage.movers() == 0);

  node::UpdatePlan<T, B> plan;
  plan.clear();
  plan.round.fill(7);
  r.stage.set_aside(r.map, *r.assoc, plan);
  CHECK(plan.alone);
  CHECK(plan.round[1] == node::UpdatePlan<T, B>::kAlone);  // the tentative pair moves only its landmark
  CHECK(plan.round[0] == 0);                               // the confirmed pair moves the pose
}

TEST_CASE_TEMPLATE("tentative: a tentative landmark that jumped is a mover, and follow() tracks it", T, float, double) {
  TentativeRig<T> r;
  r.scan(T(4), T(0.75));  // a metre to the side: outside the pairing gate
  const T d2 = individual_d2(r.obs, *r.pred, 1, 1);
  REQUIRE(d2 > r.cfg->gate.individual);
  r.stage.pair(*r.cfg, r.obs, *r.pred, 1, d2 + T(1), r.map, *r.assoc);  // inside the augmentation gate
  CHECK(r.assoc->feature[1] == kUnmatched);
  REQUIRE(r.stage.jumped() == 1);
  CHECK(r.stage.jumped(0) == r.tentative);
  CHECK(r.stage.movers() == 1);
  CHECK(r.stage.caught() == 1);

  // The next scan: a new sighting half a metre on is the mover, not a new landmark.
  r.scan(T(4), T(0.87));
  r.stage.follow(r.obs, r.map, *r.assoc);
  CHECK(r.assoc->feature[1] == kUnmatched);
  CHECK(r.assoc->feature[0] == r.ids[0]);  // a paired observation is left alone
  // Far from the mover: still new.
  r.scan(T(9), T(-1));
  r.stage.follow(r.obs, r.map, *r.assoc);
  CHECK(r.assoc->feature[1] == kNewFeature);
}

TEST_CASE_TEMPLATE("tentative: beyond the augmentation gate nothing jumped; with no tentative candidate nothing pairs",
                   T, float, double) {
  TentativeRig<T> r;
  r.scan(T(4), T(0.75));
  const T d2 = individual_d2(r.obs, *r.pred, 1, 1);
  r.stage.pair(*r.cfg, r.obs, *r.pred, 1, d2 - T(1), r.map, *r.assoc);  // the sighting is a new landmark's
  CHECK(r.assoc->feature[1] == kNewFeature);
  CHECK(r.stage.jumped() == 0);
  CHECK(r.stage.movers() == 0);

  r.scan(T(4.02), T(0.505));
  r.stage.pair(*r.cfg, r.obs, *r.pred, 2, T(1e6), r.map, *r.assoc);  // every candidate counted confirmed
  CHECK(r.assoc->feature[1] == kNewFeature);
  CHECK(r.assoc->pairings == 1);
}
