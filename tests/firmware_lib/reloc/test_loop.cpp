// Loop closures scored, unique and confirmed (reloc/loop.hpp, node::LoopCheck): the set
// likelihood on a hand-computed case; a drifted filter's closure held while pending, committed on
// the confirming scan and then right; two pairs the prior determines taken, a look-alike held; a correction that changes between scans not committed; an
// agreeing closure left alone; a closure's duplicate merged (ids stable, P definite); the filter's
// linearisation point, pose inflation and an update in rounds; bad input a Status with nothing
// changed; no allocation; float and double agree.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "geojcbb/node/slam_step.hpp"
#include "firmware_lib/reloc/reloc_scene.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;
using geojcbb::test::allocations_during;
using geojcbb::test::observe_from;
using geojcbb::test::position_error;

namespace {

using B = DefaultBounds;

template <typename T>
using Rig = test::RelocRig<T, B>;

/// The filter at `believed` with a small (overconfident) covariance, the map known.
template <typename T>
std::unique_ptr<Rig<T>> make_rig(const std::vector<Eigen::Vector2d>& map, const Pose2<double>& believed,
                                 bool loop_check = true, bool surveyed = false) {
  StepSettings<T> s = test::reloc_settings<T>();
  s.loop_check = loop_check;
  s.loop_age = 1;
  auto rig =
      test::make_known_map_rig<T, B>(map, s, believed, Vec3<T>(T(0.01), T(0.01), T(1e-4)).asDiagonal(), surveyed);
  rig->obs.clear();
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);  // every landmark one review unseen: old
  return rig;
}

}  // namespace

TEST_CASE("loop: the set likelihood of a hand-computed case") {
  using T = double;
  reloc::AlignWorkspace<T, B> ws;
  ws.clear_map();
  REQUIRE(ws.push_landmark(Vec2<T>(5, 0), Mat2<T>::Identity() * 0.01) == Status::kOk);
  REQUIRE(ws.push_landmark(Vec2<T>(0, 5), Mat2<T>::Identity() * 0.01) == Status::kOk);
  Observations<T, B> obs;
  Mat2<T> R;
  R << 0.01, 0, 0, 1e-4;
  REQUIRE(obs.push(Vec2<T>(5, 0), R) == Status::kOk);     // landmark (5, 0), exactly
  REQUIRE(obs.push(Vec2<T>(3, -1.0), R) == Status::kOk);  // nothing there
  reloc::AlignOptions<T> view;
  view.max_range_m = 10;
  view.half_fov_rad = kPi<T>;
  reloc::AlignResult<T, B> res;
  REQUIRE(reloc::align(obs, view, ws, res) == Status::kOk);  // prepares q, S; sorts the map by x
  REQUIRE(ws.m[1].x() == 5.0);
  ws.pick[0] = 1;
  ws.pick[1] = -1;
  reloc::SetModel<T> model;
  model.p_detect = 0.8;
  model.unexplained_density = 0.002;
  // The pair: d2 0, S = J R J^T + P = diag(0.01, 25e-4) + 0.01 I, det 2.5e-4. The landmark (0, 5)
  // is in view and missed; the second observation is unexplained.
  const double expected =
      std::log(0.8) - std::log(2 * kPi<double>) - 0.5 * std::log(2.5e-4) + std::log(0.002) + std::log(1 - 0.8);
  CHECK(reloc::set_log_likelihood(ws, obs.count, Pose2<T>{}, view, model) == doctest::Approx(expected).epsilon(1e-12));
  // Moving the pose 0.1 m along x adds d2 = 0.01 / 0.02 = 0.5 to the pair: half a nat less.
  CHECK(reloc::set_log_likelihood(ws, obs.count, Pose2<T>{0.1, 0, 0}, view, model) ==
        doctest::Approx(expected - 0.25).epsilon(1e-9));
  // The view shrunk to the pair's side: no miss.
  view.half_fov_rad = 1.0;
  CHECK(reloc::set_log_likelihood(ws, obs.count, Pose2<T>{}, view, model) ==
        doctest::Approx(expected - std::log(1 - 0.8)).epsilon(1e-12));
}

TEST_CASE_TEMPLATE("loop: a drifted filter's closure is held, committed on confirmation, and right", T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4}, believed{-1.5, -2, 0.48};  // drifted 2.7 m and 4.6 degrees
  auto rig = make_rig<T>(map, believed);
  observe_from(map, truth, rig->obs);
  REQUIRE(rig->obs.count >= 8);
  const Pose2<T> before = rig->step.slam().pose();
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kPending);
  CHECK(rig->out.loop.ll_alignment >= rig->out.loop.ll_association + T(3));
  CHECK(rig->out.loop.held >= 8);
  int paired = 0;
  for (int i = 0; i < rig->out.count; ++i) paired += rig->out.outcome[i] == node::Outcome::kPaired;
  CHECK(paired == 0);  // nothing of the disputed closure reached the filter
  CHECK(std::abs(double(rig->step.slam().pose().x - before.x)) < 1e-3);
  // The same view again: the same correction wins a second time and is committed.
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kCommitted);
  paired = 0;
  for (int i = 0; i < rig->out.count; ++i) paired += rig->out.outcome[i] == node::Outcome::kPaired;
  CHECK(paired == rig->obs.count);
  CHECK(position_error(rig->step, truth) < 0.05);
  CHECK(std::abs(wrap_angle(double(rig->step.slam().pose().theta) - truth.theta)) < 0.005);
  // The scan after: the landmarks it sees were just paired (no longer old); the old ones left in
  // the region (out of view) dispute nothing, and every observation is paired as usual.
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kConsistent);
  CHECK(rig->out.loop.held == 0);
  for (int i = 0; i < rig->out.count; ++i) CHECK(rig->out.outcome[i] == node::Outcome::kPaired);
}

// Two old landmarks in view: too few for the alignment (loop_min_inliers 3), so no alternative. The
// association's closure is taken when the prior determines each pair (no other landmark of the local
// region within loop_margin_nats of it): pending, then committed with its own pairs. A look-alike
// within the pose's uncertainty leaves the pair undetermined: held, not guessed.
TEST_CASE_TEMPLATE("loop: two pairs the prior determines close the loop; a look-alike within the prior is held", T,
                   float, double) {
  const Pose2<double> truth{0, 0, 0}, believed{1.5, 0.5, 0.02};  // drifted 1.6 m
  const std::vector<Eigen::Vector2d> seen{{8, 1}, {10, -3}};
  const Mat3<T> P0 = Vec3<T>(T(1), T(1), T(0.01)).asDiagonal();
  StepSettings<T> s = test::reloc_settings<T>();
  s.loop_check = true;
  s.loop_age = 1;
  for (bool look_alike : {false, true}) {
    CAPTURE(look_alike);
    std::vector<Eigen::Vector2d> map = seen;
    if (look_alike) map.emplace_back(8.8, 1.3);  // 0.85 m from (8, 1), where the drifted pose puts it
    auto rig = test::make_known_map_rig<T, B>(map, s, believed, P0);
    rig->obs.clear();
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);  // every landmark one review unseen: old
    observe_from(seen, truth, rig->obs);                         // the look-alike is not there
    REQUIRE(rig->obs.count == 2);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    CHECK(rig->out.loop.inliers == 0);  // no alignment of two observations
    if (look_alike) {
      CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kNoAlternative);
      CHECK(rig->out.loop.held >= 1);
      REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
      CHECK(rig->out.loop.verdict != reloc::LoopVerdict::kCommitted);
      CHECK(position_error(rig->step, believed) < 0.01);  // nothing reached the filter
      continue;
    }
    CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kPending);
    CHECK(rig->out.loop.held == 2);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kCommitted);
    for (int i = 0; i < rig->out.count; ++i) {
      CHECK(rig->out.outcome[i] == node::Outcome::kPaired);
      CHECK(rig->out.feature[i] == i);  // the association's own pairs: (8, 1) is 0, (10, -3) is 1
    }
    CHECK(position_error(rig->step, truth) < 0.1);
  }
}

// A surveyed map (measured, not built by the robot) does not drift with it: re-observing it is
// localisation, never a loop closure. The drifted scene above, with the map added as surveyed: the
// check never runs, and the step answers as with the check off. A map added after a step is not
// surveyed (ids not in a row from the reset); a reset forgets the survey.
TEST_CASE_TEMPLATE("loop: a surveyed landmark is never old; the check leaves the step as it was", T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4}, believed{-1.5, -2, 0.48};
  auto surveyed = make_rig<T>(map, believed, true, true);
  auto off = make_rig<T>(map, believed, false);
  observe_from(map, truth, surveyed->obs);
  observe_from(map, truth, off->obs);
  for (int k = 0; k < 3; ++k) {
    REQUIRE(surveyed->step.step(surveyed->obs, surveyed->out) == Status::kOk);
    REQUIRE(off->step.step(off->obs, off->out) == Status::kOk);
    CHECK(surveyed->out.loop.verdict == reloc::LoopVerdict::kNone);
    for (int i = 0; i < surveyed->out.count; ++i) {
      CHECK(surveyed->out.outcome[i] == off->out.outcome[i]);
      CHECK(surveyed->out.feature[i] == off->out.feature[i]);
    }
    CHECK(surveyed->step.slam().pose().x == off->step.slam().pose().x);
  }
  // After a reset the same map added as mapped (the default): the check runs again.
  auto again = make_rig<T>(map, believed);
  observe_from(map, truth, again->obs);
  REQUIRE(again->step.step(again->obs, again->out) == Status::kOk);
  CHECK(again->out.loop.verdict == reloc::LoopVerdict::kPending);
  REQUIRE(surveyed->step.reset(Pose2<T>{T(believed.x), T(believed.y), T(believed.theta)},
                               Vec3<T>(T(0.01), T(0.01), T(1e-4)).asDiagonal()) == Status::kOk);
  for (const auto& l : map) {
    FeatureId id = -1;
    REQUIRE(surveyed->step.add_known_landmark(l.cast<T>(), Mat2<T>::Identity() * T(1e-4), id) == Status::kOk);
  }
  surveyed->obs.clear();
  REQUIRE(surveyed->step.step(surveyed->obs, surveyed->out) == Status::kOk);
  observe_from(map, truth, surveyed->obs);
  REQUIRE(surveyed->step.step(surveyed->obs, surveyed->out) == Status::kOk);
  CHECK(surveyed->out.loop.verdict == reloc::LoopVerdict::kPending);
}

TEST_CASE("loop: float and double agree: the same verdicts, pairs and committed pose") {
  const auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4}, believed{-1.5, -2, 0.48};
  auto rf = make_rig<float>(map, believed);
  auto rd = make_rig<double>(map, believed);
  observe_from(map, truth, rf->obs);
  observe_from(map, truth, rd->obs);
  REQUIRE(rf->obs.count == rd->obs.count);
  for (int scan = 0; scan < 3; ++scan) {  // pending, committed, consistent (the case above)
    CAPTURE(scan);
    REQUIRE(rf->step.step(rf->obs, rf->out) == Status::kOk);
    REQUIRE(rd->step.step(rd->obs, rd->out) == Status::kOk);
    CHECK(rf->out.loop.verdict == rd->out.loop.verdict);
    CHECK(rf->out.loop.held == rd->out.loop.held);
    for (int i = 0; i < rd->out.count; ++i) {
      CHECK(rf->out.outcome[i] == rd->out.outcome[i]);
      CHECK(rf->out.feature[i] == rd->out.feature[i]);
    }
    const Pose2<float> pf = rf->step.slam().pose();
    const Pose2<double> pd = rd->step.slam().pose();
    CHECK(std::hypot(double(pf.x) - pd.x, double(pf.y) - pd.y) < 1e-3);
    CHECK(std::abs(wrap_angle(double(pf.theta) - pd.theta)) < 1e-4);
  }
}

TEST_CASE("loop: a closure whose correction changes between scans is not committed") {
  const auto map = test::reloc_map();
  // `other` is 2.1 m from the filter's pose, within its prior (0.1 m sigma + the 1 m floor), and
  // 2.7 m from the first correction's pose.
  const Pose2<double> truth{-4, -3, 0.4}, believed{-1.5, -2, 0.48}, other{-3, -0.5, 0.45};
  auto rig = make_rig<double>(map, believed);
  observe_from(map, truth, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  REQUIRE(rig->out.loop.verdict == reloc::LoopVerdict::kPending);
  observe_from(map, other, rig->obs);  // the filter did not move; the scan says another correction
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kPending);
  CHECK(position_error(rig->step, believed) < 1e-6);
}

// The prior replaced the hard search window: a correction of 5.4 m against a filter sure to 0.1 m
// (prior d2 about 29 with the floor, over the 25.9 gate) is not a candidate, and nothing moves.
TEST_CASE("loop: a correction the prior rules out is no closure") {
  const auto map = test::reloc_map();
  const Pose2<double> believed{-1.5, -2, 0.48}, far{-6, 1, 0.3};
  auto rig = make_rig<double>(map, believed);
  observe_from(map, far, rig->obs);
  REQUIRE(rig->obs.count >= 6);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.loop.verdict != reloc::LoopVerdict::kPending);
  CHECK(rig->out.loop.verdict != reloc::LoopVerdict::kCommitted);
  CHECK(position_error(rig->step, believed) < 0.5);
}

TEST_CASE("loop: a closure the alignment agrees with is left as the association made it") {
  const auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4};
  auto rig = make_rig<double>(map, truth);
  observe_from(map, truth, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kAgreed);
  CHECK(rig->out.loop.held == 0);
  for (int i = 0; i < rig->out.count; ++i) CHECK(rig->out.outcome[i] == node::Outcome::kPaired);
}

TEST_CASE("loop: the loop check allocates nothing, and a miscounted association changes nothing") {
  const auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4}, believed{-1.5, -2, 0.48};
  auto rig = make_rig<double>(map, believed);
  observe_from(map, truth, rig->obs);
  Status st = Status::kNoConvergence;
  CHECK(allocations_during([&] { st = rig->step.step(rig->obs, rig->out); }) == 0);
  REQUIRE(st == Status::kOk);
  REQUIRE(rig->out.loop.verdict == reloc::LoopVerdict::kPending);
  const node::AssociationOverride<double, B> bad{test::miscounted_association<double, B>, nullptr};
  CHECK(rig->step.step(rig->obs, rig->out, nullptr, &bad) == Status::kInvalidInput);
  // The pending closure survived the refused scan: the next scan commits it.
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.loop.verdict == reloc::LoopVerdict::kCommitted);
}

TEST_CASE("loop: the closure check off leaves the step as it was") {
  const auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4}, believed{-1.5, -2, 0.48};
  auto off = make_rig<double>(map, believed, false);
  observe_from(map, truth, off->obs);
  REQUIRE(off->step.step(off->obs, off->out) == Status::kOk);
  CHECK(off->out.loop.verdict == reloc::LoopVerdict::kNone);
  CHECK(off->out.counts.loop == 0u);
}

TEST_CASE_TEMPLATE(
    "merge: a duplicate never observed with the landmark it repeats is merged into it; ids stay, P stays "
    "definite",
    T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4};
  int k = -1;  // the first landmark in view: it gets a duplicate, mapped 0.36 m off and unsure
  for (std::size_t j = 0; j < map.size() && k < 0; ++j) {
    const double dx = map[j].x() - truth.x, dy = map[j].y() - truth.y;
    if (std::hypot(dx, dy) < 15 && std::abs(wrap_angle(std::atan2(dy, dx) - truth.theta)) < 1.2) k = int(j);
  }
  REQUIRE(k >= 0);
  for (const T merge_d2 : {T(0), T(9.21)}) {  // off; chi2(0.99, 2)
    CAPTURE(merge_d2);
    StepSettings<T> s = test::reloc_settings<T>();
    s.duplicate_merge_d2 = merge_d2;
    auto rig = test::make_known_map_rig<T, B>(map, s, truth, Mat3<T>::Identity() * T(1e-4));
    FeatureId dup = -1;
    const Eigen::Vector2d copy = map[std::size_t(k)] + Eigen::Vector2d(0.3, -0.2);
    const Vec2<T> at(T(copy.x()), T(copy.y()));
    REQUIRE(rig->step.add_known_landmark(at, Mat2<T>::Identity() * T(0.25), dup) == Status::kOk);
    REQUIRE(dup == FeatureId(map.size()));
    rig->obs.clear();
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);  // every landmark one review unseen: old
    observe_from(map, truth, rig->obs);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);  // re-sights old landmarks: a closure
    const ekf::Slam<T, B>& slam = rig->step.slam();
    if (merge_d2 == T(0)) {
      CHECK(rig->out.review.merged == 0);
      CHECK(slam.landmarks() == int(map.size()) + 1);
      continue;
    }
    CHECK(rig->out.review.merged == 1);
    REQUIRE(slam.landmarks() == int(map.size()));
    CHECK(slam.index_of(dup) == -1);
    for (int j = 0; j < int(map.size()); ++j) CHECK(slam.id(j) == j);  // the others' ids and order
    CHECK((slam.landmark(k).template cast<double>() - map[std::size_t(k)]).norm() < 0.01);
    Eigen::MatrixXd P(slam.dim(), slam.dim());
    for (int r = 0; r < slam.dim(); ++r)
      for (int c = 0; c < slam.dim(); ++c) P(r, c) = double(slam.cov(r, c));
    CHECK(P.isApprox(P.transpose()));
    CHECK(Eigen::LLT<Eigen::MatrixXd>(P).info() == Eigen::Success);
    // The next scan, the duplicate gone: every observation pairs as before.
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    for (int i = 0; i < rig->out.count; ++i) CHECK(rig->out.outcome[i] == node::Outcome::kPaired);
  }
}

TEST_CASE_TEMPLATE("merge: two landmarks observed in one scan are distinct for good, however close", T, float, double) {
  auto map = test::reloc_map();
  const Pose2<double> truth{-4, -3, 0.4};
  int k = -1;  // the first landmark in view: a second one 1.5 m from it, not known, is observed with it
  for (std::size_t j = 0; j < map.size() && k < 0; ++j) {
    const double dx = map[j].x() - truth.x, dy = map[j].y() - truth.y;
    if (std::hypot(dx, dy) < 15 && std::abs(wrap_angle(std::atan2(dy, dx) - truth.theta)) < 1.2) k = int(j);
  }
  REQUIRE(k >= 0);
  auto both = map;
  both.push_back(map[std::size_t(k)] + Eigen::Vector2d(1.5, 0.0));
  StepSettings<T> s = test::reloc_settings<T>();
  s.augment = true;
  s.duplicate_merge_d2 = T(1000);  // lenient: only the memory keeps the two apart
  s.landmark_delete_nats = -1000;  // misses do not remove the new landmark: only a merge could
  auto rig = test::make_known_map_rig<T, B>(map, s, truth, Mat3<T>::Identity() * T(1e-4));
  observe_from(both, truth, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  const FeatureId added = FeatureId(map.size());
  int news = 0;
  for (int i = 0; i < rig->out.count; ++i) news += rig->out.outcome[i] == node::Outcome::kNewLandmark;
  REQUIRE(news == 1);
  const ekf::Slam<T, B>& slam = rig->step.slam();
  REQUIRE(slam.index_of(added) >= 0);
  // Close enough for the merge test: without the memory the next scan, which misses it, merges them.
  CHECK(slam.duplicate_d2(k, slam.index_of(added)) < T(1000));
  for (int scan = 0; scan < 3; ++scan) {
    observe_from(map, truth, rig->obs);  // the second one missed
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    CHECK(rig->out.review.merged == 0);
    CHECK(slam.index_of(added) >= 0);
  }
  CHECK(slam.landmarks() == int(map.size()) + 1);
}

TEST_CASE_TEMPLATE("ekf: an update linearised at the estimate is the plain update; inflate_pose", T, float, double) {
  ekf::Slam<T, B> a, b;
  const Pose2<T> x0{T(1), T(2), T(0.3)};
  const Mat3<T> P0 = Vec3<T>(T(0.04), T(0.04), T(0.01)).asDiagonal();
  REQUIRE(a.reset(x0, P0) == Status::kOk);
  REQUIRE(b.reset(x0, P0) == Status::kOk);
  FeatureId id = -1;
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  REQUIRE(a.augment(Vec2<T>(T(5), T(0.2)), R, id) == Status::kOk);
  REQUIRE(b.augment(Vec2<T>(T(5), T(0.2)), R, id) == Status::kOk);
  Observations<T, B> obs;
  REQUIRE(obs.push(Vec2<T>(T(5.1), T(0.21)), R) == Status::kOk);
  Association<T, B> assoc;
  assoc.count = 1;
  assoc.feature[0] = id;
  ekf::SlamWorkspace<T, B> ws;
  const Pose2<T> at = a.pose();
  REQUIRE(a.update(obs, assoc, ws) == Status::kOk);
  REQUIRE(b.update(obs, assoc, ws, &at) == Status::kOk);
  for (int r = 0; r < b.dim(); ++r) {
    CHECK(a.x(r) == b.x(r));
    for (int c = 0; c < b.dim(); ++c) CHECK(a.cov(r, c) == b.cov(r, c));
  }
  const Pose2<T> nan_pose{std::numeric_limits<T>::quiet_NaN(), T(0), T(0)};
  CHECK(b.update(obs, assoc, ws, &nan_pose) == Status::kNonFinite);
  // Inflation: Q added to the pose block, the pose-landmark correlation kept.
  const T p02 = b.cov(0, 3), p00 = b.cov(0, 0);
  REQUIRE(b.inflate_pose(Vec3<T>(T(1), T(2), T(0.1)).asDiagonal()) == Status::kOk);
  CHECK(b.cov(0, 0) == doctest::Approx(double(p00 + T(1))));
  CHECK(b.cov(0, 3) == p02);
  const Mat3<T> Prr = b.pose_covariance();
  CHECK(b.inflate_pose(Vec3<T>(T(-1), T(0), T(0)).asDiagonal()) == Status::kNotPositiveDefinite);
  Mat3<T> asym = Mat3<T>::Zero();
  asym(0, 1) = T(1);
  CHECK(b.inflate_pose(asym) == Status::kNotSymmetric);
  CHECK(b.inflate_pose(Vec3<T>(std::numeric_limits<T>::infinity(), T(0), T(0)).asDiagonal()) == Status::kNonFinite);
  CHECK(b.pose_covariance() == Prr);
  CHECK(b.replace_pose_covariance(-Prr) == Status::kNotPositiveDefinite);
  CHECK(b.pose_covariance() == Prr);
}

TEST_CASE_TEMPLATE("ekf: an update in rounds takes each round's pairs alone, at the estimate the rounds before left", T,
                   float, double) {
  // A committed closure's pairs go in rounds (SlamStep::kClosureRounds): round r of update() must
  // be the update with only that round's pairs, bit for bit, and the rounds one after the other the
  // sequential updates.
  ekf::Slam<T, B> a, b;
  const Pose2<T> x0{T(1), T(2), T(0.3)};
  const Mat3<T> P0 = Vec3<T>(T(0.04), T(0.04), T(0.01)).asDiagonal();
  REQUIRE(a.reset(x0, P0) == Status::kOk);
  REQUIRE(b.reset(x0, P0) == Status::kOk);
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  const Vec2<T> z0[3] = {Vec2<T>(T(5), T(0.2)), Vec2<T>(T(4), T(-0.5)), Vec2<T>(T(6), T(1.0))};
  FeatureId ids[3] = {-1, -1, -1};
  for (int k = 0; k < 3; ++k) {
    REQUIRE(a.augment(z0[k], R, ids[k]) == Status::kOk);
    REQUIRE(b.augment(z0[k], R, ids[k]) == Status::kOk);
  }
  Observations<T, B> obs;
  for (int k = 0; k < 3; ++k) REQUIRE(obs.push(z0[k] + Vec2<T>(T(0.1), T(0.01) * T(k + 1)), R) == Status::kOk);
  Association<T, B> all;
  all.count = 3;
  for (int k = 0; k < 3; ++k) all.feature[k] = ids[k];
  const std::uint8_t rounds[3] = {1, 0, 1};  // observation 1 first, then 0 and 2
  ekf::SlamWorkspace<T, B> ws;
  const Pose2<T> at{T(1.05), T(1.95), T(0.31)};
  // a: in rounds; b: the same pairs as separate associations.
  REQUIRE(a.update(obs, all, ws, &at, rounds, 0) == Status::kOk);
  Association<T, B> first = all, second = all;
  first.feature[0] = first.feature[2] = kUnmatched;
  second.feature[1] = kUnmatched;
  REQUIRE(b.update(obs, first, ws, &at) == Status::kOk);
  for (int r = 0; r < b.dim(); ++r) CHECK(a.x(r) == b.x(r));
  REQUIRE(a.update(obs, all, ws, nullptr, rounds, 1) == Status::kOk);
  REQUIRE(b.update(obs, second, ws) == Status::kOk);
  for (int r = 0; r < b.dim(); ++r) {
    CHECK(a.x(r) == b.x(r));
    for (int c = 0; c < b.dim(); ++c) CHECK(a.cov(r, c) == b.cov(r, c));
  }
  // A round with no pair changes nothing.
  const Pose2<T> before = a.pose();
  REQUIRE(a.update(obs, all, ws, nullptr, rounds, 2) == Status::kOk);
  CHECK(a.pose().x == before.x);
  CHECK(a.pose().theta == before.theta);
}
