// Local maps (docs/submaps.md): ekf::Slam::restart re-expresses the kept landmarks in the robot's
// frame with the covariance J P J^T and lets the ids go on; seed_landmark adds a correlated landmark;
// node::SlamStep's closing rule reports a map due after its landmarks, distance or scans.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>

#include <Eigen/Dense>

#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;
using namespace geojcbb::ekf;
using geojcbb::test::allocations_during;

namespace {
using SB = Bounds<16, 24, 5, 1000, 40>;

// A small map: three landmarks seen from a pose that has moved and turned, one update, so the pose
// and the landmarks are correlated.
template <typename T>
void build(Slam<T, SB>& slam, SlamWorkspace<T, SB>& ws) {
  REQUIRE(slam.reset(Pose2<T>{T(1), T(-2), T(0.3)}, Mat3<T>(Vec3<T>(T(0.04), T(0.03), T(0.002)).asDiagonal())) ==
          Status::kOk);
  const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.01), T(0.0004)).asDiagonal());
  FeatureId id = -1;
  REQUIRE(slam.augment(Vec2<T>(T(5), T(0.2)), R, id) == Status::kOk);
  REQUIRE(slam.augment(Vec2<T>(T(7), T(-0.6)), R, id) == Status::kOk);
  REQUIRE(slam.augment(Vec2<T>(T(4), T(1.1)), R, id) == Status::kOk);
  REQUIRE(slam.predict(Odometry<T>{T(1), T(0.2), T(1), T(0.1), T(0.05)}) == Status::kOk);
  Observations<T, SB> obs;
  Association<T, SB> assoc;
  REQUIRE(obs.push(Vec2<T>(T(4.2), T(0.05)), R) == Status::kOk);
  assoc.count = 1;
  assoc.feature[0] = 0;
  REQUIRE(slam.update(obs, assoc, ws) == Status::kOk);
}

Eigen::MatrixXd dense(const Slam<double, SB>& slam) {
  const int n = slam.dim();
  Eigen::MatrixXd P(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) P(r, c) = slam.cov(r, c);
  return P;
}
}  // namespace

TEST_CASE("restart: kept landmarks in the robot's frame with J P J^T, the pose at the origin, the ids going on") {
  auto slam = std::make_unique<Slam<double, SB>>();
  auto ws = std::make_unique<SlamWorkspace<double, SB>>();
  build(*slam, *ws);
  const Eigen::MatrixXd P = dense(*slam);
  const Pose2<double> p = slam->pose();
  const FeatureId next = slam->next_id();
  const FeatureId id0 = slam->id(0), id2 = slam->id(2);
  // The expectation, written out: l' = R^T (l - p) for landmarks 0 and 2, J over [pose, l0, l1, l2].
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  Eigen::Matrix2d Rt;
  Rt << c, s, -s, c;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(4, slam->dim());
  Eigen::Vector4d expect;
  const int kept_index[2] = {0, 2};
  for (int k = 0; k < 2; ++k) {
    const int r = Layout::landmark(kept_index[k]);
    const Eigen::Vector2d d = Rt * Eigen::Vector2d(slam->x(r) - p.x, slam->x(r + 1) - p.y);
    expect.segment<2>(2 * k) = d;
    J.block<2, 2>(2 * k, 0) = -Rt;
    J(2 * k, 2) = d.y();
    J(2 * k + 1, 2) = -d.x();
    J.block<2, 2>(2 * k, r) = Rt;
  }
  const Eigen::Matrix4d expect_P = J * P * J.transpose();
  const Mat3<double> P0 = Mat3<double>::Identity() * 1e-6;
  std::int16_t keep[SB::kMaxLandmarks] = {2, 0};
  CHECK(slam->restart(P0, keep, 2) == Status::kInvalidInput);  // not increasing: nothing changes
  CHECK(slam->landmarks() == 3);
  CHECK(dense(*slam).isApprox(P, 0));
  keep[0] = 0;
  keep[1] = 2;
  Status st = Status::kNoConvergence;
  CHECK(allocations_during([&] { st = slam->restart(P0, keep, 2); }) == 0);
  REQUIRE(st == Status::kOk);
  CHECK(slam->landmarks() == 2);
  CHECK(slam->id(0) == id0);
  CHECK(slam->id(1) == id2);
  CHECK(slam->next_id() == next);  // the ids go on: the next map's landmarks are told apart
  CHECK(slam->pose().x == 0);
  CHECK(slam->pose().theta == 0);
  const Eigen::MatrixXd Q = dense(*slam);
  CHECK(Q.topLeftCorner<3, 3>().isApprox(P0, 1e-12));
  CHECK(Q.topRightCorner(3, 4).norm() == 0);  // the new origin is exact: no correlation with it
  for (int k = 0; k < 2; ++k) {
    CHECK(slam->landmark(k).x() == doctest::Approx(expect(2 * k)).epsilon(1e-12));
    CHECK(slam->landmark(k).y() == doctest::Approx(expect(2 * k + 1)).epsilon(1e-12));
  }
  CHECK((Q.bottomRightCorner(4, 4) - expect_P).norm() < 1e-12 * expect_P.norm());
  // Nothing kept: an empty map, the ids still going on.
  std::int16_t none[SB::kMaxLandmarks] = {};
  REQUIRE(slam->restart(P0, none, 0) == Status::kOk);
  CHECK(slam->landmarks() == 0);
  FeatureId id = -1;
  REQUIRE(slam->augment(Vec2<double>(3, 0), Mat2<double>::Identity() * 0.01, id) == Status::kOk);
  CHECK(id == next);
}

TEST_CASE(
    "seed_landmark: a confirmed landmark with its existence, uncorrelated with the map; bad input refused, nothing changed") {
  auto slam = std::make_unique<Slam<double, SB>>();
  REQUIRE(slam->reset(Pose2<double>{0, 0, 0}, Mat3<double>::Identity() * 1e-6) == Status::kOk);
  FeatureId a = -1, b = -1;
  Mat2<double> Pa;
  Pa << 0.04, 0.01, 0.01, 0.09;
  REQUIRE(slam->seed_landmark(Vec2<double>(3, 1), Pa, 100.0, a) == Status::kOk);
  Mat2<double> bad = Pa;
  bad(1, 1) = -1;
  CHECK(slam->seed_landmark(Vec2<double>(5, 1), bad, 100.0, b) == Status::kNotPositiveDefinite);
  CHECK(slam->seed_landmark(Vec2<double>(5, std::nan("")), Pa, 100.0, b) == Status::kNonFinite);
  CHECK(slam->seed_landmark(Vec2<double>(5, 1), Pa, std::nan(""), b) == Status::kNonFinite);
  CHECK(slam->landmarks() == 1);
  REQUIRE(slam->seed_landmark(Vec2<double>(5, 1), Pa, 7.5, b) == Status::kOk);
  CHECK(slam->confirmed(0));
  CHECK(slam->confirmed(1));
  CHECK(slam->existence(0) == 100.0);  // as given: the evidence banked where it was made
  CHECK(slam->existence(1) == 7.5);
  CHECK(b == a + 1);
  const int la = Layout::landmark(0), lb = Layout::landmark(1);
  CHECK(slam->cov(lb, lb + 1) == 0.01);
  CHECK(slam->cov(lb + 1, lb + 1) == 0.09);
  CHECK(slam->cov(la, lb) == 0);  // uncorrelated with the other seed
  CHECK(slam->cov(lb, 0) == 0);   // and with the pose
}

TEST_CASE("closing rule: a map is due after its landmarks (once it has added one), its distance or its scans") {
  using B = SB;
  auto s = std::make_unique<node::SlamStep<double, B>>();
  auto res = std::make_unique<node::StepResult<double, B>>();
  node::StepSettings<double> st;
  st.local_radius_m = 15;
  st.min_range_m = 0.5;
  st.max_range_m = 10;
  st.half_fov_rad = 1.4;
  st.submap_landmarks = 2;
  REQUIRE(s->configure(st) == Status::kOk);
  REQUIRE(s->reset(Pose2<double>{0, 0, 0}, Mat3<double>::Identity() * 1e-4) == Status::kOk);
  Observations<double, B> obs;
  const Mat2<double> R = Mat2<double>(Vec2<double>(0.01, 0.0003).asDiagonal());
  REQUIRE(obs.push(Vec2<double>(4, 0.1), R) == Status::kOk);
  REQUIRE(s->step(obs, *res) == Status::kOk);
  CHECK(!res->submap_due);  // one landmark
  REQUIRE(obs.push(Vec2<double>(6, -0.8), R) == Status::kOk);
  REQUIRE(s->step(obs, *res) == Status::kOk);
  CHECK(res->submap_due);  // two
  // The next map carries both (confirmed, in the region): it is not due until it adds its own.
  REQUIRE(s->step(obs, *res) == Status::kOk);  // confirms them
  REQUIRE(s->restart() == Status::kOk);
  CHECK(s->slam().landmarks() == 2);
  CHECK(s->scans_in_map() == 0);
  REQUIRE(s->step(obs, *res) == Status::kOk);
  CHECK(!res->submap_due);
  // Distance and scans.
  st.submap_landmarks = 0;
  st.submap_distance_m = 1.5;
  REQUIRE(s->configure(st) == Status::kOk);
  REQUIRE(s->reset(Pose2<double>{0, 0, 0}, Mat3<double>::Identity() * 1e-4) == Status::kOk);
  REQUIRE(s->predict(ekf::Odometry<double>{1, 0, 1, 0.05, 0.01}) == Status::kOk);
  REQUIRE(s->step(obs, *res) == Status::kOk);
  CHECK(!res->submap_due);
  REQUIRE(s->predict(ekf::Odometry<double>{1, 0, 1, 0.05, 0.01}) == Status::kOk);
  CHECK(s->travelled_m() == doctest::Approx(2));
  REQUIRE(s->step(obs, *res) == Status::kOk);
  CHECK(res->submap_due);
  st.submap_distance_m = 0;
  st.submap_scans = 3;
  REQUIRE(s->configure(st) == Status::kOk);
  REQUIRE(s->reset(Pose2<double>{0, 0, 0}, Mat3<double>::Identity() * 1e-4) == Status::kOk);
  for (int k = 1; k <= 3; ++k) {
    REQUIRE(s->step(obs, *res) == Status::kOk);
    CHECK(res->submap_due == (k == 3));
  }
}

TEST_CASE(
    "seed: room is the capacity less one scan, not the region's candidates; a seed banks the global map's "
    "existence, capped at the policy's saturation") {
  using B = Bounds<5, 6, 5, 1000, 21>;  // 6 candidates, 21 landmarks: room for 21 - 5 = 16 seeds
  auto s = std::make_unique<node::SlamStep<double, B>>();
  node::StepSettings<double> st;
  st.local_radius_m = 15;
  st.max_range_m = 10;
  REQUIRE(s->configure(st) == Status::kOk);
  REQUIRE(s->reset(Pose2<double>{0, 0, 0}, Mat3<double>::Identity() * 1e-4) == Status::kOk);
  node::MapSeed<double> in[node::kMaxSeeds];
  node::SeedAnswer<double> out[node::kMaxSeeds];
  auto seed_ring = [&](int call) {  // 8 seeds 3 m apart, all within the region (r + d = 15 m)
    for (int k = 0; k < node::kMaxSeeds; ++k) {
      const double a = 0.39 * (8 * call + k);
      in[k].l = Vec2<double>(3 + 0.5 * call, 0) + 2.0 * Vec2<double>(std::cos(a), std::sin(a)) * (1 + call);
      in[k].P = Mat2<double>::Identity() * 0.01;
      in[k].exist_nats = k == 0 ? 1e6 : 10.0 + k;  // the first over the saturation
    }
    return s->seed(in, node::kMaxSeeds, out);
  };
  REQUIRE(seed_ring(0) == Status::kOk);
  REQUIRE(seed_ring(1) == Status::kOk);
  CHECK(s->slam().landmarks() == 16);  // more than the region's 6 candidates: the nearest are predicted
  for (int k = 0; k < node::kMaxSeeds; ++k) CHECK(out[k].outcome == node::Outcome::kNewLandmark);
  const ekf::LandmarkPolicy policy;
  for (int j = 0; j < 16; ++j) {  // as given, the first of each call capped
    const int k = j % node::kMaxSeeds;
    CHECK(s->slam().existence(j) == doctest::Approx(k == 0 ? policy.confirm_nats + policy.reserve_nats : 10.0 + k));
  }
  REQUIRE(seed_ring(2) == Status::kOk);  // no room left for a scan's new landmarks
  CHECK(s->slam().landmarks() == 16);
  for (int k = 0; k < node::kMaxSeeds; ++k) {
    CHECK(out[k].outcome == node::Outcome::kNotAugmented);
    CHECK(out[k].id == kNewFeature);
  }
  // A closing size below the capacity bounds the seeds too: seeds alone never make the map due.
  st.submap_landmarks = 10;
  REQUIRE(s->configure(st) == Status::kOk);
  REQUIRE(s->reset(Pose2<double>{0, 0, 0}, Mat3<double>::Identity() * 1e-4) == Status::kOk);
  REQUIRE(seed_ring(0) == Status::kOk);
  REQUIRE(seed_ring(1) == Status::kOk);
  CHECK(s->slam().landmarks() == 10);
  CHECK(out[1].outcome == node::Outcome::kNewLandmark);
  CHECK(out[2].outcome == node::Outcome::kNotAugmented);
  // Bad parameters: refused, nothing seeded.
  auto slam = std::make_unique<Slam<double, B>>();
  REQUIRE(slam->reset(Pose2<double>{0, 0, 0}, Mat3<double>::Identity() * 1e-4) == Status::kOk);
  CHECK(node::seed_map(*slam, 9.2, std::nan(""), 16, in, 1, out) == Status::kInvalidInput);
  const double exist = in[0].exist_nats;
  in[0].exist_nats = std::nan("");  // a seed's existence not finite: no seed taken
  CHECK(node::seed_map(*slam, 9.2, 100.0, 16, in, 1, out) == Status::kNonFinite);
  in[0].exist_nats = exist;
  CHECK(node::seed_map(*slam, 9.2, 100.0, 17, in, 1, out) == Status::kInvalidInput);  // over 21 - 5
  CHECK(node::seed_map(*slam, 9.2, 100.0, 16, in, node::kMaxSeeds + 1, out) == Status::kInvalidInput);
  CHECK(slam->landmarks() == 0);
  REQUIRE(node::seed_map(*slam, 9.2, 100.0, 16, in, 1, out) == Status::kOk);
  CHECK(slam->landmarks() == 1);
}
