// node/wire.hpp's reply to an OBS_BATCH on its own, over results built by hand: to_wire(StepResult)
// as ASSOC_RESULT (each outcome's feature id by the wire's rule, d2 in float32, the count and batch
// id) and to_wire(Slam) as POSE (pose, covariance, landmark count, the ids removed, the hand-over's
// frame count). Both allocate nothing, and what they build is a valid frame. And CONFIG, generated
// from the option table: one field per option in the table's order, each option through the wire.
#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <tuple>

#include "geojcbb/node/wire.hpp"
#include "support/alloc_counter.hpp"
#include "support/options.hpp"

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

namespace {
/// The options on which a and b differ, by name ("" when none).
template <typename T>
std::string differing(const StepSettings<T>& a, const StepSettings<T>& b) {
  std::string names;
  for_each_option_pair(a, b, [&](const options::Info& info, const auto& x, const auto& y) {
    if (!(x == y)) names += std::string(info.name) + " ";
  });
  return names;
}

template <std::size_t... K>
void check_field_names(std::index_sequence<K...>) {
  const std::array<const char*, sizeof...(K)> names{std::get<K>(proto::Config::fields()).name...};
  for (int k = 0; k < options::kCount; ++k) {
    CAPTURE(k);
    CHECK(std::string(names[static_cast<std::size_t>(k)]) == options::kInfo[k].name);
  }
  CHECK(std::string(names.back()) == "stats_period_scans");
}
}  // namespace

TEST_CASE("wire: CONFIG is the option table, line by line, then the device's own field") {
  static_assert(node::config_wire::kFieldCount == options::kCount + 1, "one CONFIG field per option, and one more");
  check_field_names(std::make_index_sequence<node::config_wire::kFieldCount>{});
}

TEST_CASE("wire: every option of the table round-trips through CONFIG's bytes") {
  const StepSettings<float> defaults_on_device = node::settings_from<float, B>(proto::Config{});
  for (int k = 0; k < options::kCount; ++k) {
    const std::string option = options::kInfo[k].name;
    CAPTURE(option);
    const StepSettings<float> s = test::with_other<float>(k);  // this option away from its default
    REQUIRE(in_range(s));
    const proto::Config c = node::config_from(s);
    const proto::Config back = through_the_wire(c);
    const StepSettings<float> got = node::settings_from<float, B>(back);
    // What the device runs is what the host's settings say at float32, and only this option differs
    // from a device left at its defaults.
    CHECK(differing(got, node::settings_from<float, B>(c)) == "");
    CHECK(differing(got, defaults_on_device) == option + " ");
  }
  // The defaults, and the device's own field.
  proto::Config c = node::config_from(StepSettings<float>{});
  c.stats_period_scans = 7;
  const proto::Config back = through_the_wire(c);
  CHECK(differing(node::settings_from<float, B>(back), defaults_on_device) == "");
  CHECK(back.stats_period_scans == 7);
}
