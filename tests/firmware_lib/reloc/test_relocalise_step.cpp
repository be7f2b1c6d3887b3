// The relocaliser in the SLAM step (node/slam_step.hpp) and on the wire (RELOCALISE): a constructed
// kidnap found in one scan and confirmed on the next; a wrong confirming scan sends the robot back to
// lost with the covariance it had, or, after a doubt, back to the pose it tracked; a lost scan that cannot be aligned changes nothing but the state;
// the relocaliser off leaves the step as it was; a device given RELOCALISE re-sets its covariance and is
// lost; no allocation.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "geojcbb/node/node.hpp"
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

/// A step with the relocaliser, the map known (the true landmarks), the robot at `x0`.
template <typename T>
std::unique_ptr<Rig<T>> make_rig(const std::vector<Eigen::Vector2d>& map, const Pose2<double>& x0, bool reloc = true) {
  StepSettings<T> s = test::reloc_settings<T>();
  s.relocalise = reloc;
  return test::make_known_map_rig<T, B>(map, s, x0, Mat3<T>::Identity() * T(1e-4));
}

Mat3<double> kidnap_cov() { return Vec3<double>(225, 225, 9.8).asDiagonal(); }

}  // namespace

TEST_CASE_TEMPLATE("reloc step: a kidnap is found in one scan and confirmed on the next", T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> before{-5, -5, 0.3}, after{6, 4, 2.4};  // carried 14 m and 120 degrees
  auto rig = make_rig<T>(map, before);
  REQUIRE(rig->step.relocalise(rig->step.slam().pose(), kidnap_cov().cast<T>()) == Status::kOk);
  rig->step.lost();
  CHECK(rig->step.localisation() == node::Localisation::kLost);
  observe_from(map, after, rig->obs);
  REQUIRE(rig->obs.count >= 6);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.reloc.aligned);
  CHECK(rig->out.reloc.relocalised);
  CHECK(!rig->out.reloc.found);
  CHECK(rig->out.reloc.state == node::Localisation::kConfirming);
  CHECK(position_error(rig->step, after) < 0.05);
  CHECK(std::abs(wrap_angle(double(rig->step.slam().pose().theta) - after.theta)) < 0.005);
  int paired = 0;
  for (int i = 0; i < rig->out.count; ++i) paired += rig->out.outcome[i] == node::Outcome::kPaired;
  CHECK(paired == rig->obs.count);  // associated as usual at the aligned pose
  // The next scan (the robot did not move) confirms it.
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.reloc.found);
  CHECK(!rig->out.reloc.aligned);
  CHECK(rig->step.localisation() == node::Localisation::kTracking);
}

// A large covariance is uncertainty, not lost (docs/relocalisation.md): the variance triggers are retired. A long
// drift's honest covariance (36 m^2 of position variance, past the retired 25 m^2 trigger) keeps the
// robot tracking, and the association closes the 1.5 m error over the next scans.
TEST_CASE_TEMPLATE("reloc step: a large but honest covariance keeps the robot tracking", T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> at{-5, -5, 0.3};
  auto rig = make_rig<T>(map, at);
  const Mat3<T> P = Vec3<T>(T(18), T(18), T(0.05)).asDiagonal();
  REQUIRE(rig->step.relocalise(Pose2<T>{T(-3.5), T(-5), T(0.3)}, P) == Status::kOk);
  observe_from(map, at, rig->obs);
  REQUIRE(rig->obs.count >= 6);
  double error = position_error(rig->step, at);
  for (int k = 1; k <= 3; ++k) {
    CAPTURE(k);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    CHECK(!rig->out.reloc.aligned);
    CHECK(rig->out.reloc.doubt == 0);  // every landmark in view paired: evidence for the pose
    CHECK(rig->step.localisation() == node::Localisation::kTracking);
    int paired = 0;
    for (int i = 0; i < rig->out.count; ++i) paired += rig->out.outcome[i] == node::Outcome::kPaired;
    CHECK(paired >= 3);
    CHECK(position_error(rig->step, at) < error);  // each scan closes more of it
    error = position_error(rig->step, at);
  }
  CHECK(error < 0.2);
}

// The lost test (docs/design.md, "Decisions with the prior"): scans the tracked pose does not explain (landmarks in view missed, none
// paired) add up as evidence against it (a CUSUM); past reloc_lost_nats the scan is aligned
// pose-free while still tracked, and a pose beyond the filter's prior is a kidnap.
TEST_CASE_TEMPLATE("reloc step: a kidnap the covariance does not show is doubted by the lost test, then found", T,
                   float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> before{-5, -5, 0.3}, after{6, 4, 2.4};  // carried 14 m and 120 degrees
  for (double h : {0.0, 20.0}) {
    CAPTURE(h);
    StepSettings<T> s = test::reloc_settings<T>();
    s.relocalise = true;
    s.reloc_lost_nats = T(h);
    auto rig = test::make_known_map_rig<T, B>(map, s, before, Mat3<T>::Identity() * T(1e-4));
    observe_from(map, after, rig->obs);  // the filter is sure it is still at `before`
    REQUIRE(rig->obs.count >= 6);
    int doubted_at = 0, relocalised_at = 0;
    float doubt = 0;
    for (int k = 1; k <= 6 && relocalised_at == 0; ++k) {
      REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
      CHECK(rig->step.localisation() != node::Localisation::kLost);  // doubted, never lost: every scan is used
      if (rig->out.reloc.doubted && doubted_at == 0) doubted_at = k;
      if (rig->out.reloc.relocalised) relocalised_at = k;
      if (relocalised_at == 0 && !rig->out.reloc.doubted) {
        CHECK(rig->out.reloc.doubt >= doubt);  // the evidence against the pose adds up
        doubt = rig->out.reloc.doubt;
      }
    }
    if (h > 0) {
      CHECK(doubted_at >= 2);  // one scan is not enough at 20 nats
      CHECK(relocalised_at == doubted_at);
      CHECK(position_error(rig->step, after) < 0.05);
    } else {
      CHECK(doubted_at == 0);  // off: the filter never notices
      CHECK(doubt == 0);
      CHECK(position_error(rig->step, after) > 10);
    }
  }
}

TEST_CASE_TEMPLATE("reloc step: a doubted pose that the alignment finds within the prior is kept", T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> at{-5, -5, 0.3};
  StepSettings<T> s = test::reloc_settings<T>();
  s.relocalise = true;
  s.reloc_lost_nats = T(20);
  auto rig = test::make_known_map_rig<T, B>(map, s, at, Mat3<T>::Identity() * T(1e-4));
  // Empty scans: every landmark in view missed, evidence against the pose.
  int k = 0;
  for (; k < 10 && rig->out.reloc.doubt < 20; ++k) {
    rig->obs.count = 0;
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    CHECK(!rig->out.reloc.aligned);
  }
  REQUIRE(rig->out.reloc.doubt >= 20);
  const Pose2<T> x = rig->step.slam().pose();
  observe_from(map, at, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.reloc.doubted);
  CHECK(rig->out.reloc.aligned);
  CHECK(rig->out.reloc.cleared);  // the aligned pose lies within the prior: the pose stands
  CHECK(!rig->out.reloc.relocalised);
  CHECK(rig->out.reloc.doubt == 0);
  CHECK(rig->step.localisation() == node::Localisation::kTracking);
  // The scan was used as usual: paired as a step that never doubted pairs it.
  StepSettings<T> off = s;
  off.reloc_lost_nats = T(0);
  auto twin = test::make_known_map_rig<T, B>(map, off, at, Mat3<T>::Identity() * T(1e-4));
  observe_from(map, at, twin->obs);
  REQUIRE(twin->step.step(twin->obs, twin->out) == Status::kOk);
  int paired = 0;
  for (int i = 0; i < rig->out.count; ++i) {
    paired += rig->out.outcome[i] == node::Outcome::kPaired;
    CHECK(rig->out.outcome[i] == twin->out.outcome[i]);
    CHECK(rig->out.feature[i] == twin->out.feature[i]);
  }
  CHECK(paired >= 6);
  CHECK(std::abs(double(rig->step.slam().pose().x - x.x)) < 0.05);
}

TEST_CASE_TEMPLATE("reloc step: a confirming scan that does not fit sends the robot back to lost", T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> before{-5, -5, 0.3}, after{6, 4, 2.4}, elsewhere{-8, 6, -1.0};
  auto rig = make_rig<T>(map, before);
  REQUIRE(rig->step.relocalise(rig->step.slam().pose(), kidnap_cov().cast<T>()) == Status::kOk);
  rig->step.lost();
  observe_from(map, after, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  REQUIRE(rig->out.reloc.relocalised);
  // Carried again before the confirming scan: what it sees does not fit the aligned pose.
  observe_from(map, elsewhere, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.reloc.rejected);
  CHECK(rig->step.localisation() == node::Localisation::kLost);
  CHECK(double(rig->step.slam().cov(0, 0)) == doctest::Approx(225).epsilon(1e-6));
  CHECK(double(rig->step.slam().cov(2, 2)) == doctest::Approx(9.8).epsilon(1e-6));
  // And the scan after finds it where it is.
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.reloc.relocalised);
  CHECK(position_error(rig->step, elsewhere) < 0.05);
}

TEST_CASE_TEMPLATE(
    "reloc step: a jump after a doubt that the next scan does not bear out goes back to the tracked pose", T, float,
    double) {
  // Not lost: the pose it tracked is still the best it has. It stays tracked, doubted as it was, and
  // the scan after is aligned pose-free again (before, it was lost and searched without a prior).
  const auto map = test::reloc_map();
  const Pose2<double> before{-5, -5, 0.3}, after{6, 4, 2.4}, elsewhere{-8, 6, -1.0};
  StepSettings<T> s = test::reloc_settings<T>();
  s.relocalise = true;
  s.reloc_lost_nats = T(20);
  auto rig = test::make_known_map_rig<T, B>(map, s, before, Mat3<T>::Identity() * T(1e-4));
  observe_from(map, after, rig->obs);  // kidnapped; the filter is sure it is still at `before`
  Pose2<T> tracked{};
  Mat3<T> tracked_cov = Mat3<T>::Zero();
  float doubt = 0;
  for (int k = 0; k < 6 && !rig->out.reloc.relocalised; ++k) {
    tracked = rig->step.slam().pose();
    tracked_cov = rig->step.slam().pose_covariance();
    doubt = rig->out.reloc.doubt;
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  }
  REQUIRE(rig->out.reloc.relocalised);
  REQUIRE(rig->out.reloc.doubted);
  REQUIRE(doubt >= 20);
  // Carried again before the confirming scan: the jump is not borne out.
  observe_from(map, elsewhere, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.reloc.rejected);
  CHECK(rig->step.localisation() == node::Localisation::kTracking);
  CHECK(rig->out.reloc.doubt == doctest::Approx(doubt));
  const Pose2<T> x = rig->step.slam().pose();
  CHECK(std::abs(double(x.x - tracked.x)) < 1e-4);
  CHECK(std::abs(double(x.y - tracked.y)) < 1e-4);
  CHECK(std::abs(double(wrap_angle(x.theta - tracked.theta))) < 1e-4);
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) CHECK(double(rig->step.slam().cov(a, b)) == doctest::Approx(double(tracked_cov(a, b))));
  }
  // Still doubted: the scan after is aligned pose-free and found where it is.
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(rig->out.reloc.doubted);
  CHECK(rig->out.reloc.relocalised);
  CHECK(position_error(rig->step, elsewhere) < 0.05);
}

TEST_CASE_TEMPLATE("reloc step: a lost scan that cannot be aligned changes nothing", T, float, double) {
  const auto map = test::reloc_map();
  const Pose2<double> before{-5, -5, 0.3};
  auto rig = make_rig<T>(map, before);
  REQUIRE(rig->step.relocalise(rig->step.slam().pose(), kidnap_cov().cast<T>()) == Status::kOk);
  rig->step.lost();
  // Two observations: too few for a pose.
  rig->obs.clear();
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  REQUIRE(rig->obs.push(Vec2<T>(T(5), T(0.1)), R) == Status::kOk);
  REQUIRE(rig->obs.push(Vec2<T>(T(9), T(-0.4)), R) == Status::kOk);
  const Pose2<T> x = rig->step.slam().pose();
  const int n = rig->step.slam().landmarks();
  std::uint64_t allocations = 0;
  Status st = Status::kNoConvergence;
  allocations = allocations_during([&] { st = rig->step.step(rig->obs, rig->out); });
  REQUIRE(st == Status::kOk);
  CHECK(allocations == 0);
  CHECK(rig->out.reloc.aligned);
  CHECK(!rig->out.reloc.relocalised);
  CHECK(rig->step.localisation() == node::Localisation::kLost);
  CHECK(rig->step.slam().pose().x == x.x);
  CHECK(rig->step.slam().pose().theta == x.theta);
  CHECK(rig->step.slam().landmarks() == n);
  for (int i = 0; i < rig->out.count; ++i) CHECK(rig->out.outcome[i] == node::Outcome::kUnmatched);
}

TEST_CASE("reloc step: the relocaliser off, lost() and a large covariance change nothing") {
  const auto map = test::reloc_map();
  const Pose2<double> before{-5, -5, 0.3};
  auto rig = make_rig<double>(map, before, false);
  REQUIRE(rig->step.relocalise(rig->step.slam().pose(), kidnap_cov()) == Status::kOk);
  rig->step.lost();
  CHECK(rig->step.localisation() == node::Localisation::kTracking);
  observe_from(map, before, rig->obs);
  REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  CHECK(!rig->out.reloc.aligned);
  CHECK(rig->out.reloc.state == node::Localisation::kTracking);
}

TEST_CASE("reloc step: a device given RELOCALISE re-sets its covariance and is lost") {
  using NB = DefaultBounds;
  auto node = std::make_unique<node::Node<float, NB>>();
  std::vector<std::uint8_t> sink;
  node->start(node::Output{&sink,
                           [](void* c, const std::uint8_t* p, std::size_t n) {
                             auto& b = *static_cast<std::vector<std::uint8_t>*>(c);
                             b.insert(b.end(), p, p + n);
                           }},
              7);
  auto feed = [&](const auto& m, std::uint16_t seq) {
    proto::EncodedFrame f;
    REQUIRE(proto::encode_message(m, seq, 0, f) == proto::Error::kOk);
    node->on_bytes(f.bytes.data(), f.size);
  };
  feed(proto::Hello{}, 0);
  proto::Config c;
  c.relocalise = true;
  feed(c, 1);
  feed(proto::Reset{}, 2);
  proto::Relocalise r;
  r.cov_upper = {225.0f, 0.0f, 0.0f, 225.0f, 0.0f, 9.8f};
  feed(r, 3);
  CHECK(node->slam_step().slam().cov(0, 0) == 225.0f);
  CHECK(node->slam_step().slam().cov(2, 2) == 9.8f);
  CHECK(node->slam_step().localisation() == node::Localisation::kLost);
  // A retransmission (the same seq) is not applied twice.
  r.cov_upper = {1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f};
  feed(r, 3);
  CHECK(node->slam_step().slam().cov(0, 0) == 225.0f);
}
