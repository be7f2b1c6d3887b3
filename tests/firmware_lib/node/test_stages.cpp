// The step's stages on their own, their inputs built by hand (not through SlamStep::step):
// SubmapClose (each limit of the closing rule, only at a settled pose; the fill level only once the
// map added a landmark; what the next map keeps; the room a seeded map has) and UpdatePlan (the pairs
// held alone move only their landmark, the others move the pose; a closure's rounds and inflation).
#include <doctest/doctest.h>

#include <cmath>
#include <memory>

#include "geojcbb/node/stages/submap_close.hpp"
#include "geojcbb/node/update_plan.hpp"

using namespace geojcbb;

namespace {

using B = DefaultBounds;

/// A filter at (1, 2, 0.3) with two landmarks made from observations (tentative: not confirmed), then
/// driven 0.5 m ahead (the pose no longer the one the landmarks were made from: a pair moves it).
template <typename T>
std::unique_ptr<ekf::Slam<T, B>> two_landmarks(FeatureId& a, FeatureId& b, Mat2<T>& R) {
  auto s = std::make_unique<ekf::Slam<T, B>>();
  REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.3)}, Vec3<T>(T(0.04), T(0.04), T(0.01)).asDiagonal()) == Status::kOk);
  R << T(0.01), T(0), T(0), T(3e-4);
  REQUIRE(s->augment(Vec2<T>(T(5), T(0.2)), R, a) == Status::kOk);
  REQUIRE(s->augment(Vec2<T>(T(4), T(-0.5)), R, b) == Status::kOk);
  REQUIRE(s->predict(ekf::Odometry<T>{T(0.5), T(0), T(1), T(0.1), T(0.05)}) == Status::kOk);
  return s;
}

/// Both landmarks observed again, a little off, and paired.
template <typename T>
void observe_both(const Mat2<T>& R, FeatureId a, FeatureId b, Observations<T, B>& obs, Association<T, B>& assoc) {
  obs.clear();
  REQUIRE(obs.push(Vec2<T>(T(5.2), T(0.22)), R) == Status::kOk);
  REQUIRE(obs.push(Vec2<T>(T(3.9), T(-0.48)), R) == Status::kOk);
  assoc = Association<T, B>{};
  assoc.count = 2;
  assoc.feature[0] = a;
  assoc.feature[1] = b;
  assoc.candidate[0] = assoc.candidate[1] = -1;
  assoc.pairings = 2;
}

/// One scan of the two landmarks, paired, and what the plan needs.
template <typename T>
struct PlanRig {
  FeatureId a = -1, b = -1;
  Mat2<T> R;
  std::unique_ptr<ekf::Slam<T, B>> s = two_landmarks<T>(a, b, R);
  Observations<T, B> obs;
  std::unique_ptr<Association<T, B>> assoc = std::make_unique<Association<T, B>>();
  std::unique_ptr<ekf::SlamWorkspace<T, B>> ws = std::make_unique<ekf::SlamWorkspace<T, B>>();
  node::UpdatePlan<T, B> plan;
  PlanRig() {
    observe_both(R, a, b, obs, *assoc);
    plan.clear();
    plan.round.fill(0);
  }
};

}  // namespace

TEST_CASE("submap close: each limit at a settled pose, the fill level once a landmark was added") {
  using T = double;
  AssociationConfig<T, B> cfg;
  node::SubmapClose<T, B> c;
  c.begin();
  CHECK_FALSE(c.due(cfg, true, B::kMaxLandmarks));  // every limit off
  cfg.submap_scans = 3;
  c.scan();
  c.scan();
  CHECK_FALSE(c.due(cfg, true, 0));
  c.scan();
  CHECK(c.due(cfg, true, 0));
  CHECK_FALSE(c.due(cfg, false, 0));  // not settled: lost, a closure pending, a window open
  cfg.submap_scans = 0;
  cfg.submap_distance_m = 10;
  c.travelled(9.5);
  CHECK_FALSE(c.due(cfg, true, 0));
  c.travelled(0.5);
  CHECK(c.due(cfg, true, 0));
  c.begin();
  CHECK(c.travelled_m() == 0.0);
  CHECK(c.scans() == 0);
  CHECK_FALSE(c.due(cfg, true, 0));
  cfg.submap_distance_m = 0;
  cfg.submap_landmarks = 20;
  CHECK_FALSE(c.due(cfg, true, 30));  // began fuller (carried over, seeded): not closed at once
  c.added = 1;
  CHECK_FALSE(c.due(cfg, true, 19));
  CHECK(c.due(cfg, true, 20));
  CHECK(node::SubmapClose<T, B>::room(cfg) == 20);
  cfg.submap_landmarks = 0;
  CHECK(node::SubmapClose<T, B>::room(cfg) == B::kMaxLandmarks - B::kMaxObservations);
}

TEST_CASE("submap close: the next map keeps the confirmed landmarks of the last scan's region, with submap_carry") {
  using T = double;
  auto s = std::make_unique<ekf::Slam<T, B>>();
  REQUIRE(s->reset(Pose2<T>{T(0), T(0), T(0)}, Mat3<T>::Identity() * T(1e-4)) == Status::kOk);
  FeatureId ids[3] = {-1, -1, -1};
  for (int k = 0; k < 3; ++k) {  // known: confirmed
    REQUIRE(s->add_known_landmark(Vec2<T>(T(2 + k), T(1)), Mat2<T>::Identity() * T(1e-4), ids[k]) == Status::kOk);
  }
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  FeatureId tentative = -1;
  REQUIRE(s->augment(Vec2<T>(T(3), T(-0.3)), R, tentative) == Status::kOk);
  const ekf::LandmarkPolicy policy;
  const node::MapView<T, B> map(*s, policy);
  auto pred = std::make_unique<Prediction<T, B>>();
  pred->count = 3;  // the region: landmarks 0 and 2 and the tentative one
  pred->id[0] = ids[0];
  pred->id[1] = ids[2];
  pred->id[2] = tentative;
  AssociationConfig<T, B> cfg;
  cfg.submap_carry = true;
  std::int16_t keep[B::kMaxLandmarks];
  REQUIRE(node::SubmapClose<T, B>::kept(cfg, map, *pred, keep) == 2);
  CHECK(keep[0] == s->index_of(ids[0]));
  CHECK(keep[1] == s->index_of(ids[2]));
  cfg.submap_carry = false;
  CHECK(node::SubmapClose<T, B>::kept(cfg, map, *pred, keep) == 0);
}

TEST_CASE_TEMPLATE("update plan: a pair held alone moves only its landmark; the rest of the scan moves the pose", T,
                   float, double) {
  PlanRig<T> rig;
  auto& s = rig.s;
  auto& plan = rig.plan;
  const FeatureId b = rig.b;
  const Mat2<T> R = rig.R;
  plan.round[1] = node::UpdatePlan<T, B>::kAlone;
  plan.alone = true;
  const Pose2<T> x0 = s->pose();
  const Vec2<T> lb0 = s->landmark(s->index_of(b));
  // Only observation 0 in the filter's update: the same as a scan without observation 1.
  FeatureId a2 = -1, b2 = -1;  // the same ids again
  Mat2<T> R2;
  auto only = two_landmarks<T>(a2, b2, R2);
  Observations<T, B> obs0;
  REQUIRE(obs0.push(rig.obs.z[0], R) == Status::kOk);
  auto assoc0 = std::make_unique<Association<T, B>>(*rig.assoc);
  assoc0->count = 1;
  assoc0->pairings = 1;
  REQUIRE(only->update(obs0, *assoc0, *rig.ws, nullptr, nullptr, 0) == Status::kOk);
  REQUIRE(plan.apply(rig.obs, *rig.assoc, *s, *rig.ws) == Status::kOk);
  CHECK(s->pose().x == doctest::Approx(only->pose().x));  // observation 1 moved nothing but its landmark
  CHECK(s->pose().y == doctest::Approx(only->pose().y));
  CHECK(s->pose().theta == doctest::Approx(only->pose().theta));
  CHECK(std::abs(s->pose().x - x0.x) > T(1e-4));
  CHECK((s->landmark(s->index_of(b)) - lb0).norm() > T(0));
}

TEST_CASE_TEMPLATE("update plan: a closure inflates the pose block and applies its rounds; off, nothing inflates", T,
                   float, double) {
  PlanRig<T> plain, closed;
  REQUIRE(plain.plan.apply(plain.obs, *plain.assoc, *plain.s, *plain.ws) == Status::kOk);
  auto& plan = closed.plan;
  plan.close.commit = true;
  plan.close.at = closed.s->pose();
  plan.close.Q = Mat3<T>::Identity() * T(1);
  plan.round[1] = 1;  // the second pair in the second round
  REQUIRE(plan.apply(closed.obs, *closed.assoc, *closed.s, *closed.ws) == Status::kOk);
  // The inflated pose follows the observations further than the plain update does.
  CHECK(std::abs(closed.s->pose().x - plain.s->pose().x) > T(0));
  CHECK(closed.s->pose_covariance()(0, 0) > plain.s->pose_covariance()(0, 0));
}
