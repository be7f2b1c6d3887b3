// node/wire.hpp's reply to an OBS_BATCH on its own, over results built by hand: to_wire(StepResult)
// as ASSOC_RESULT (each outcome's feature id by the wire's rule, d2 in float32, the count and batch
// id) and to_wire(Slam) as POSE (pose, covariance, landmark count, the ids removed, the hand-over's
// frame count). Both allocate nothing, and what they build is a valid frame.
#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <memory>

#include "geojcbb/node/wire.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {

using B = DefaultBounds;
using AssocResult = proto::AssocResultT<static_cast<std::size_t>(B::kMaxObservations)>;

/// The message passes the wire's validation and survives encode and decode whole.
template <class M>
M through_the_wire(const M& m) {
  std::array<std::uint8_t, M::kMaxPayloadSize> buf{};
  std::size_t len = 0;
  REQUIRE(m.encode(buf, len) == proto::Error::kOk);
  M back{};
  REQUIRE(back.decode(buf.data(), len) == proto::Error::kOk);
  return back;
}

}  // namespace

TEST_CASE_TEMPLATE("wire: a step's result as ASSOC_RESULT, one observation of each outcome", T, float, double) {
  auto r = std::make_unique<node::StepResult<T, B>>();
  using node::Outcome;
  const std::array<Outcome, 6> outcome{Outcome::kPaired,    Outcome::kNewLandmark,  Outcome::kNewDropped,
                                       Outcome::kUnmatched, Outcome::kNotAugmented, Outcome::kMover};
  // The step's own ids: a landmark's for paired and new landmark; what the association left otherwise.
  const std::array<FeatureId, 6> feature{7, 12, kNewFeature, kUnmatched, kNewFeature, kUnmatched};
  const T inf = std::numeric_limits<T>::infinity();
  const std::array<T, 6> d2{T(1.25), inf, inf, T(3.5), inf, T(0.5)};
  r->count = 6;
  for (std::size_t i = 0; i < 6; ++i) {
    r->outcome[i] = outcome[i];
    r->feature[i] = feature[i];
    r->d2[i] = d2[i];
  }
  AssocResult a;
  const std::uint64_t allocations = test::allocations_during([&] { node::to_wire(*r, 0xCAFEu, a); });
  CHECK(allocations == 0);

  CHECK(a.batch_id == 0xCAFEu);
  CHECK(a.count == 6);
  const std::array<std::int32_t, 6> want_id{
      7, 12, proto::kFeatureNew, proto::kFeatureUnmatched, proto::kFeatureNew, proto::kFeatureUnmatched};
  for (std::size_t i = 0; i < 6; ++i) {
    CAPTURE(i);
    CHECK(static_cast<int>(a.pairs[i].outcome) == static_cast<int>(outcome[i]));
    CHECK(a.pairs[i].feature_id == want_id[i]);
    CHECK(a.pairs[i].d2 == static_cast<float>(d2[i]));
  }
  // A valid frame (feature_id >= 0 exactly for paired and new landmark), whole through the codec.
  const AssocResult back = through_the_wire(a);
  CHECK(back.count == 6);
  CHECK(back.pairs[1].feature_id == 12);
  CHECK(back.pairs[5].outcome == proto::PairingOutcome::kMover);
}

TEST_CASE_TEMPLATE("wire: a mover keeps no id on the wire even when the step gave it one", T, float, double) {
  // The wire's rule: only paired and new-landmark pairings name a landmark.
  auto r = std::make_unique<node::StepResult<T, B>>();
  r->count = 2;
  r->outcome[0] = node::Outcome::kMover;
  r->feature[0] = 3;
  r->outcome[1] = node::Outcome::kNotAugmented;
  r->feature[1] = 4;
  AssocResult a;
  node::to_wire(*r, 1, a);
  CHECK(a.pairs[0].feature_id == proto::kFeatureUnmatched);
  CHECK(a.pairs[1].feature_id == proto::kFeatureNew);
  CHECK(a.validate() == proto::Error::kOk);
}

TEST_CASE_TEMPLATE("wire: an empty scan and a full one", T, float, double) {
  auto r = std::make_unique<node::StepResult<T, B>>();
  AssocResult a;
  node::to_wire(*r, 2, a);
  CHECK(a.count == 0);
  CHECK(through_the_wire(a).count == 0);
  r->unused(B::kMaxObservations);  // a scan not used: every observation unmatched, d2 infinite
  node::to_wire(*r, 3, a);
  REQUIRE(a.count == B::kMaxObservations);
  for (const proto::PairingWire& q : a.pairs) {
    CHECK(q.outcome == proto::PairingOutcome::kUnmatched);
    CHECK(q.feature_id == proto::kFeatureUnmatched);
    CHECK(q.d2 == std::numeric_limits<float>::infinity());
  }
  CHECK(through_the_wire(a).count == B::kMaxObservations);
}

TEST_CASE_TEMPLATE("wire: the filter after a step as POSE", T, float, double) {
  auto s = std::make_unique<ekf::Slam<T, B>>();
  Mat3<T> P;
  P << T(0.04), T(0.01), T(0.002), T(0.01), T(0.05), T(0.003), T(0.002), T(0.003), T(0.01);
  REQUIRE(s->reset(Pose2<T>{T(1.5), T(-2), T(0.25)}, P) == Status::kOk);
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  FeatureId a = -1, b = -1;
  REQUIRE(s->augment(Vec2<T>(T(5), T(0.2)), R, a) == Status::kOk);
  REQUIRE(s->augment(Vec2<T>(T(4), T(-0.5)), R, b) == Status::kOk);
  REQUIRE(s->forget(a) == Status::kOk);

  proto::Pose p;
  const std::uint64_t allocations = test::allocations_during([&] { node::to_wire(*s, 41u, false, p); });
  CHECK(allocations == 0);
  CHECK(p.batch_id == 41u);
  CHECK(p.x_m == static_cast<float>(s->x(0)));
  CHECK(p.y_m == static_cast<float>(s->x(1)));
  CHECK(p.theta_rad == static_cast<float>(s->x(2)));
  const std::array<float, 6> upper{static_cast<float>(s->cov(0, 0)), static_cast<float>(s->cov(0, 1)),
                                   static_cast<float>(s->cov(0, 2)), static_cast<float>(s->cov(1, 1)),
                                   static_cast<float>(s->cov(1, 2)), static_cast<float>(s->cov(2, 2))};
  CHECK(p.cov_upper == upper);
  CHECK(p.landmark_count == 1);
  REQUIRE(p.removed == 1);
  REQUIRE(p.count == 1);
  CHECK(p.ids[0].feature_id == a);
  CHECK(p.submap_frames == 0);
  CHECK(through_the_wire(p).landmark_count == 1);

  // Handing the local map over: POSE announces its frames.
  node::to_wire(*s, 42u, true, p);
  CHECK(p.submap_frames == proto::submap_frames(1));
  CHECK(p.submap_frames > 0);
}

