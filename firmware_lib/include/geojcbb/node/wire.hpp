// node: the wire and the library side by side. The definitions protocol/ restates (strategy codes,
// pairing outcomes, feature ids, node budgets, seeds and observations per frame) held equal at compile
// time; CONFIG (generated from the option table, core/options.h) converted both ways; an OBS_BATCH,
// ODOMETRY and RESET as the filter's inputs, and a step's result as the device's reply (ASSOC_RESULT,
// POSE). Used by the Node (node/node.hpp) on the device, and by the host to check and build what it
// sends. Compile-time checks and O(fields) or
// O(observations) conversions; no state.
#pragma once

#include <cstddef>
#include <tuple>
#include <type_traits>
#include <utility>

#include "geojcbb/node/slam_step.hpp"
#include "geojcbb/protocol/protocol.hpp"

namespace geojcbb::node {

// The wire (protocol/, standard library only) restates a few firmware definitions; here both are
// visible, so they are held equal at compile time.
namespace wire_agreement {
constexpr bool same_strategies() {
  using S = geojcbb::Strategy;
  using C = proto::StrategyCode;
  return static_cast<int>(proto::kStrategyCodeCount) == kStrategyCount &&
         static_cast<int>(S::kIcnn) == static_cast<int>(C::kIcnn) &&
         static_cast<int>(S::kJcbb) == static_cast<int>(C::kJcbb) &&
         static_cast<int>(S::kKjcbb) == static_cast<int>(C::kKjcbb) &&
         static_cast<int>(S::kDfjcbb) == static_cast<int>(C::kDfjcbb) &&
         static_cast<int>(S::kGemjcbb) == static_cast<int>(C::kGemjcbb) &&
         static_cast<int>(S::kGeojcbb) == static_cast<int>(C::kGeojcbb) &&
         static_cast<int>(S::kPcjcbb) == static_cast<int>(C::kPcjcbb);
}
constexpr bool same_outcomes() {
  using P = proto::PairingOutcome;
  return static_cast<int>(Outcome::kPaired) == static_cast<int>(P::kPaired) &&
         static_cast<int>(Outcome::kNewLandmark) == static_cast<int>(P::kNewLandmark) &&
         static_cast<int>(Outcome::kNewDropped) == static_cast<int>(P::kNewDropped) &&
         static_cast<int>(Outcome::kUnmatched) == static_cast<int>(P::kUnmatched) &&
         static_cast<int>(Outcome::kNotAugmented) == static_cast<int>(P::kNotAugmented) &&
         static_cast<int>(Outcome::kMover) == static_cast<int>(P::kMover) &&
         static_cast<int>(Outcome::kMover) == static_cast<int>(proto::kMaxPairingOutcome);
}
}  // namespace wire_agreement
static_assert(wire_agreement::same_strategies(), "geojcbb::Strategy and CONFIG's strategy code, value for value");
static_assert(wire_agreement::same_outcomes(), "node::Outcome and ASSOC_RESULT's outcome, value for value");
static_assert(kNewFeature == proto::kFeatureNew && kUnmatched == proto::kFeatureUnmatched,
              "ASSOC_RESULT's feature ids NEW and UNMATCHED are the association's");
static_assert(std::is_same<decltype(proto::Config::node_budget), NodeCount>::value,
              "CONFIG's node budget is the library's NodeCount");
static_assert(std::is_same<decltype(proto::Capabilities::max_jcbb_nodes), NodeCount>::value,
              "CAPABILITIES' node budget is the library's NodeCount");
static_assert(static_cast<std::size_t>(kMaxSeeds) == proto::kSeedsPerFrame, "SUBMAP_SEED's seeds per frame");
static_assert(static_cast<std::size_t>(DefaultBounds::kMaxObservations) == proto::kDefaultMaxObsPerBatch,
              "the wire's default batch size is DefaultBounds' observations per scan");

/// CONFIG's fields and the option table (core/options.h): protocol/messages.hpp generates one field
/// per option from the table, then the device's own stats_period_scans. The checks below state what
/// that generation must give, at compile time: the name exists in the table, the wire type suits the
/// option's TYPE, and CONFIG's default is the table's. The two conversions below are the only code
/// between the wire and the settings, generated from CONFIG's field list.
namespace config_wire {

constexpr int kFieldCount = static_cast<int>(std::tuple_size<decltype(proto::Config::fields())>::value);

/// Index of field K's option, or -1 for a field of the device's own.
template <std::size_t K>
constexpr int option_of() {
  return options::index_of(std::get<K>(proto::Config::fields()).name);
}
template <std::size_t K>
constexpr bool device_only() {
  return options::same_name(std::get<K>(proto::Config::fields()).name, "stats_period_scans");
}

/// The wire types each TYPE of the table travels as.
template <class W>
constexpr bool suits(const char* type) {
  using options::same_name;
  if (std::is_same<W, proto::StrategyCode>::value) return same_name(type, "STRATEGY");
  if (std::is_same<W, float>::value) return same_name(type, "F64") || same_name(type, "REAL") || same_name(type, "F32");
  if (std::is_same<W, bool>::value) return same_name(type, "BOOL");
  if (std::is_same<W, std::uint8_t>::value) return same_name(type, "INT");
  if (std::is_same<W, std::uint32_t>::value) return same_name(type, "U32");
  return false;
}

using options::convert;

template <std::size_t K>
constexpr bool field_tied() {
  constexpr auto f = std::get<K>(proto::Config::fields());
  using W = std::remove_reference_t<decltype(proto::Config{}.*(f.member))>;
  constexpr int i = option_of<K>();
  if constexpr (i < 0) {
    return device_only<K>();
  } else {
    constexpr StepSettings<float> d{};
    constexpr proto::Config c{};
    return suits<W>(options::kInfo[i].type) && c.*(f.member) == convert<W>(options::Member<i>::get(d));
  }
}
template <std::size_t... K>
constexpr bool all_tied(std::index_sequence<K...>) {
  return (field_tied<K>() && ...);
}
static_assert(all_tied(std::make_index_sequence<kFieldCount>{}),
              "each CONFIG field names an option of core/options.h, with a wire type that suits its TYPE and the "
              "table's default (or is the device's own stats_period_scans)");

template <std::size_t K>
constexpr bool field_carries(int option) {
  return option_of<K>() == option;
}
template <std::size_t... K>
constexpr bool carries(int option, std::index_sequence<K...>) {
  return (field_carries<K>(option) || ...);
}

template <std::size_t K, typename T>
void to_settings(const proto::Config& m, StepSettings<T>& s) {
  constexpr auto f = std::get<K>(proto::Config::fields());
  constexpr int i = option_of<K>();
  if constexpr (i >= 0) {
    auto& v = options::Member<i>::get(s);
    v = convert<std::remove_reference_t<decltype(v)>>(m.*(f.member));
  }
}
template <std::size_t K, typename T>
void to_config(const StepSettings<T>& s, proto::Config& m) {
  constexpr auto f = std::get<K>(proto::Config::fields());
  constexpr int i = option_of<K>();
  if constexpr (i >= 0) {
    auto& w = m.*(f.member);
    w = convert<std::remove_reference_t<decltype(w)>>(options::Member<i>::get(s));
  }
}
template <typename T, std::size_t... K>
void settings_from(const proto::Config& m, StepSettings<T>& s, std::index_sequence<K...>) {
  (to_settings<K>(m, s), ...);
}
template <typename T, std::size_t... K>
void config_from(const StepSettings<T>& s, proto::Config& m, std::index_sequence<K...>) {
  (to_config<K>(s, m), ...);
}

}  // namespace config_wire

/// The option with this index (options::Index) is a CONFIG field: a device runs it as the host sets
/// it. A host refuses to stream work to a device when an option the wire does not carry differs
/// from its default.
constexpr bool carried_by_config(int option) {
  return config_wire::carries(option, std::make_index_sequence<config_wire::kFieldCount>{});
}

/// CONFIG's fields as the SLAM step's settings (validated by SlamStep::configure); an option CONFIG
/// does not carry keeps its default.
template <typename T, class B>
StepSettings<T> settings_from(const proto::Config& m) {
  StepSettings<T> s;
  config_wire::settings_from(m, s, std::make_index_sequence<config_wire::kFieldCount>{});
  return s;
}

/// The settings as CONFIG (the host's side; stats_period_scans stays 0). Levels and real values are
/// rounded to float32.
template <typename T>
proto::Config config_from(const StepSettings<T>& s) {
  proto::Config m;
  config_wire::config_from(s, m, std::make_index_sequence<config_wire::kFieldCount>{});
  return m;
}

/// An OBS_BATCH as observations. @return kOk; kCapacityExceeded; kNonFinite (decode validated it).
template <typename T, class B, std::size_t MaxObs>
[[nodiscard]] Status observations_from(const proto::ObsBatchT<MaxObs>& m, Observations<T, B>& out) {
  out.clear();
  for (std::size_t i = 0; i < m.count; ++i) {  // <= MaxObs
    const proto::ObservationWire& o = m.obs[i];
    Mat2<T> R;
    R << T(o.r00), T(o.r01), T(o.r01), T(o.r11);
    const Status st = out.push(Vec2<T>(T(o.range_m), T(o.bearing_rad)), R);
    if (st != Status::kOk) return st;
  }
  return Status::kOk;
}

/// The device's reply to an OBS_BATCH: the step's result as ASSOC_RESULT. Per observation its outcome,
/// the landmark's id where it has one (paired, new landmark), else UNMATCHED (unmatched, a mover's) or
/// NEW (dropped, not augmented), and its d2 in float32. O(observations).
template <typename T, class B, std::size_t MaxObs>
void to_wire(const StepResult<T, B>& r, std::uint32_t batch_id, proto::AssocResultT<MaxObs>& out) {
  static_assert(MaxObs >= static_cast<std::size_t>(B::kMaxObservations) && MaxObs <= 255,
                "ASSOC_RESULT holds every observation of a scan, counted in a byte");
  out.batch_id = batch_id;
  out.count = static_cast<std::uint8_t>(r.count);
  for (int i = 0; i < r.count; ++i) {  // <= kMaxObservations
    const std::size_t k = static_cast<std::size_t>(i);
    const Outcome o = r.outcome[k];
    proto::PairingWire& q = out.pairs[k];
    q.outcome = static_cast<proto::PairingOutcome>(o);
    q.feature_id = o == Outcome::kPaired || o == Outcome::kNewLandmark ? r.feature[k]
                   : o == Outcome::kUnmatched || o == Outcome::kMover  ? proto::kFeatureUnmatched
                                                                       : proto::kFeatureNew;
    q.d2 = static_cast<float>(r.d2[k]);
  }
}

/// The reply's second frame: the filter after the step as POSE (pose, its covariance's upper
/// triangle, the landmark count and the ids the scan removed); `submap_frames` announces the local
/// map's hand-over when `handing_over` (0 otherwise). O(kRemovedPerPose).
template <typename T, class B>
void to_wire(const ekf::Slam<T, B>& s, std::uint32_t batch_id, bool handing_over, proto::Pose& p) {
  static_assert(ekf::RemovedIds::kMaxIds == static_cast<int>(proto::kRemovedPerPose), "POSE names them all");
  p.batch_id = batch_id;
  p.x_m = static_cast<float>(s.x(0));
  p.y_m = static_cast<float>(s.x(1));
  p.theta_rad = static_cast<float>(s.x(2));
  p.cov_upper = {static_cast<float>(s.cov(0, 0)), static_cast<float>(s.cov(0, 1)), static_cast<float>(s.cov(0, 2)),
                 static_cast<float>(s.cov(1, 1)), static_cast<float>(s.cov(1, 2)), static_cast<float>(s.cov(2, 2))};
  p.landmark_count = static_cast<std::uint16_t>(s.landmarks());
  const ekf::RemovedIds& gone = s.removed();
  p.removed = gone.count;
  p.count = static_cast<std::uint8_t>(gone.count < proto::kRemovedPerPose ? gone.count : proto::kRemovedPerPose);
  for (std::size_t k = 0; k < p.count; ++k) p.ids[k].feature_id = gone.ids[k];  // <= kRemovedPerPose
  p.submap_frames =
      handing_over ? static_cast<std::uint16_t>(proto::submap_frames(static_cast<std::uint32_t>(s.landmarks()))) : 0;
}

/// ODOMETRY as the filter's input.
template <typename T>
ekf::Odometry<T> odometry_from(const proto::Odometry& m) {
  return ekf::Odometry<T>{T(m.v_mps), T(m.w_radps), T(m.dt_s), T(m.sigma_v_mps), T(m.sigma_w_radps)};
}

/// RESET's pose and covariance.
template <typename T>
void reset_from(const proto::Reset& m, Pose2<T>& x0, Mat3<T>& P) {
  const auto& u = m.cov_upper;
  P << T(u[0]), T(u[1]), T(u[2]), T(u[1]), T(u[3]), T(u[4]), T(u[2]), T(u[4]), T(u[5]);
  x0 = Pose2<T>{T(m.x_m), T(m.y_m), T(m.theta_rad)};
}

}  // namespace geojcbb::node
