// protocol: the messages, each described once. A message is a plain struct whose fields() lists its
// fields in wire order with their valid ranges, units and notes (fields.hpp); encode, decode,
// validate, the payload sizes, its line of the schema text and its byte table in docs/protocol.md
// all come from that list. Inputs: payload bytes from the wire (untrusted). Outputs: a struct whose
// every field passed validation, or an Error with the struct untouched. Bounds: counted lists hold at
// most MaxObs items (a template parameter, default kDefaultMaxObsPerBatch), checked against
// kMaxPayload at compile time. The end of this file assembles the schema text and its hash.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "geojcbb/core/options.h"
#include "geojcbb/protocol/error.hpp"
#include "geojcbb/protocol/fields.hpp"
#include "geojcbb/protocol/frame.hpp"
#include "geojcbb/protocol/schema.hpp"
#include "geojcbb/protocol/stage_counts.h"

namespace geojcbb::proto {

/// Message type numbers. 0x01-0x0F control, 0x10-0x1F streams to the device, 0x20-0x2F results,
/// 0x30-0x3F diagnostics, 0x7F ERROR.
enum class MsgType : std::uint8_t {
  kHello = 0x01,         ///< host -> device
  kCapabilities = 0x02,  ///< device -> host
  kConfig = 0x03,        ///< host -> device, acknowledged
  kAck = 0x04,
  kNack = 0x05,
  kPing = 0x06,
  kPong = 0x07,
  kReset = 0x08,         ///< host -> device, acknowledged
  kShutdown = 0x09,      ///< host -> device, acknowledged, then the board's shutdown hook
  kRelocalise = 0x0A,    ///< host -> device, stream
  kSubmapAck = 0x0B,     ///< host -> device, acknowledged
  kOdometry = 0x10,      ///< host -> device, stream
  kObsBatch = 0x11,      ///< host -> device, stream
  kOdomDelta = 0x12,     ///< host -> device, stream
  kSubmapSeed = 0x13,    ///< host -> device, stream: global landmarks for the current local map
  kAssocResult = 0x20,   ///< device -> host
  kPose = 0x21,          ///< device -> host
  kSubmap = 0x22,        ///< device -> host, a closed local map's header and landmarks
  kSubmapCov = 0x23,     ///< device -> host, its covariance
  kStatsRequest = 0x30,  ///< host -> device
  kStats = 0x31,         ///< device -> host
  kError = 0x7F,         ///< device -> host
};

/// Observations per OBS_BATCH (and pairings per ASSOC_RESULT) by default: DefaultBounds' 24
/// (node/wire.hpp static_asserts the agreement).
constexpr std::size_t kDefaultMaxObsPerBatch = 24;

/// The schema hash (defined at the end of this file, from every message's description).
constexpr std::uint32_t current_schema_hash();

namespace detail {

/// Checks a 2x2 or 3x3 symmetric matrix for positive definiteness by an LDLᵀ factorisation in
/// double (Cholesky without square roots: every pivot d_k must be > 0; equivalent to Sylvester's
/// leading minors, numerically steadier). Symmetric by construction: only the upper triangle exists.
inline bool spd2(float a00, float a01, float a11) {
  const double d0 = a00;
  if (!(d0 > 0.0)) return false;
  const double l10 = a01 / d0;
  const double d1 = static_cast<double>(a11) - l10 * a01;
  return d1 > 0.0;
}
/// Upper triangle u = (p00, p01, p02, p11, p12, p22).
inline bool spd3(const std::array<float, 6>& u) {
  const double d0 = u[0];
  if (!(d0 > 0.0)) return false;
  const double l10 = u[1] / d0;
  const double l20 = u[2] / d0;
  const double d1 = static_cast<double>(u[3]) - l10 * l10 * d0;
  if (!(d1 > 0.0)) return false;
  const double l21 = (static_cast<double>(u[4]) - l20 * l10 * d0) / d1;
  const double d2 = static_cast<double>(u[5]) - l20 * l20 * d0 - l21 * l21 * d1;
  return d2 > 0.0;
}
/// The range of a reported error code: kBadLength .. the last Error.
constexpr Range reportable_error() {
  return range::between(static_cast<std::int64_t>(Error::kBadLength), static_cast<std::int64_t>(kErrorCount) - 1);
}
/// Names of the pose covariance's upper triangle on the wire, over (x, y, theta).
inline constexpr const char* kCovUpperNames[6] = {"p00", "p01", "p02", "p11", "p12", "p22"};

}  // namespace detail

/// A code a NACK or ERROR may carry: a real error (not kOk, not kIncomplete) of this schema.
constexpr bool is_reportable(Error e) {
  const auto v = static_cast<std::uint8_t>(e);
  return v >= static_cast<std::uint8_t>(Error::kBadLength) && v < kErrorCount;
}

// ---------------------------------------------------------------------------------------------

/// HELLO, host -> device: opens a session. The device answers CAPABILITIES, or NACK with
/// kBadVersion / kSchemaMismatch (see check_hello).
struct Hello : Codec<Hello> {
  static constexpr MsgType kType = MsgType::kHello;
  static constexpr const char* kName = "HELLO";

  std::uint8_t protocol_version = kProtocolVersion;
  std::uint32_t schema_hash = current_schema_hash();

  static constexpr auto fields() {
    return std::make_tuple(
        field("protocol_version", &Hello::protocol_version, range::any(), "", "the device refuses ≠ 1 (`check_hello`)"),
        field("schema_hash", &Hello::schema_hash, range::any(), "", "the device refuses ≠ `kSchemaHash`"));
  }
};

/// CAPABILITIES, device -> host: the device's compile-time bounds and identity.
struct Capabilities : Codec<Capabilities> {
  static constexpr MsgType kType = MsgType::kCapabilities;
  static constexpr const char* kName = "CAPABILITIES";
  static constexpr std::size_t kFirmwareIdSize = 16;

  std::uint8_t protocol_version = kProtocolVersion;
  std::uint32_t schema_hash = current_schema_hash();
  std::uint16_t max_observations = 1;  ///< per scan (M)
  std::uint16_t max_candidates = 1;    ///< map features offered to one association
  std::uint8_t max_groups = 1;
  std::uint16_t max_landmarks = 1;
  std::uint32_t max_jcbb_nodes = 1;                 ///< per scan
  std::uint8_t scalar_bytes = 4;                    ///< 4: float, 8: double
  std::uint32_t boot_id = 0;                        ///< changes at every boot (a host sees a reset)
  std::array<char, kFirmwareIdSize> firmware_id{};  ///< printable ASCII, zero padded

  static constexpr auto fields() {
    return std::make_tuple(
        field("protocol_version", &Capabilities::protocol_version), field("schema_hash", &Capabilities::schema_hash),
        field("max_observations", &Capabilities::max_observations, range::at_least(1), "", "per scan"),
        field("max_candidates", &Capabilities::max_candidates, range::at_least(1)),
        field("max_groups", &Capabilities::max_groups, range::at_least(1)),
        field("max_landmarks", &Capabilities::max_landmarks, range::at_least(1)),
        field("max_jcbb_nodes", &Capabilities::max_jcbb_nodes, range::at_least(1), "", "per scan"),
        field("scalar_bytes", &Capabilities::scalar_bytes, range::one_of(4, 8), "B", "4 float, 8 double"),
        field("boot_id", &Capabilities::boot_id, range::any(), "", "changes at every boot"),
        field("firmware_id", &Capabilities::firmware_id, range::text(), "",
              "printable ASCII (0x20–0x7E), then zero padding only"));
  }

  /// Copies text into firmware_id (truncated to 16 bytes, zero padded).
  void set_firmware_id(const char* text) {
    firmware_id.fill('\0');
    for (std::size_t i = 0; text != nullptr && i < kFirmwareIdSize && text[i] != '\0'; ++i) {  // <= 16
      firmware_id[i] = text[i];
    }
  }
};

/// Strategy numbers of CONFIG (the same order as geojcbb::Strategy; node/wire.hpp static_asserts it).
enum class StrategyCode : std::uint8_t {
  kIcnn = 0,
  kJcbb = 1,
  kKjcbb = 2,
  kDfjcbb = 3,
  kGemjcbb = 4,
  kGeojcbb = 5,
  kPcjcbb = 6
};
constexpr std::uint8_t kStrategyCodeCount = 7;

/// CONFIG's fields from the option table (core/options.h, a C table of the standard library's types
/// and literals only): the wire type each TYPE travels as, and an option's range (the table's kind,
/// lo, hi) as the wire checks it. Levels and real values travel
/// as float32; an integer range that admits every value of its wire type is no range.
namespace config_options {
struct WireTypes {
  using STRATEGY = StrategyCode;
  using F64 = float;
  using REAL = float;
  using F32 = float;
  using INT = std::uint8_t;
  using U32 = std::uint32_t;
  using BOOL = bool;
};
enum class Kind : std::uint8_t { kANY, kGT, kGE, kOPEN, kLOPEN, kROPEN, kCLOSED };

template <class W>
constexpr Range wire_range(Kind k, double lo, double hi) {
  if constexpr (std::is_same_v<W, bool>) {
    return range::one_of(0, 1);
  } else if constexpr (std::is_same_v<W, float>) {
    const auto flo = static_cast<float>(lo), fhi = static_cast<float>(hi);
    switch (k) {
      case Kind::kANY: return range::finite();
      case Kind::kGT: return range::above(flo);
      case Kind::kGE: return range::not_below(flo);
      case Kind::kOPEN: return range::interval(flo, fhi, true, true);
      case Kind::kLOPEN: return range::interval(flo, fhi, true, false);
      case Kind::kROPEN: return range::interval(flo, fhi, false, true);
      case Kind::kCLOSED: return range::interval(flo, fhi, false, false);
    }
    return range::finite();
  } else {
    using U = typename detail::Underlying<W>::type;
    constexpr auto kMax = static_cast<std::int64_t>(std::numeric_limits<U>::max());
    if (k == Kind::kANY) return range::any();
    const auto ilo = static_cast<std::int64_t>(lo) + (k == Kind::kGT || k == Kind::kOPEN || k == Kind::kLOPEN);
    const std::int64_t ihi = k == Kind::kGT || k == Kind::kGE        ? kMax
                             : k == Kind::kOPEN || k == Kind::kROPEN ? static_cast<std::int64_t>(hi) - 1
                                                                     : static_cast<std::int64_t>(hi);
    if (ilo <= 0 && ihi >= kMax) return range::any();
    return ihi >= kMax ? range::at_least(ilo) : range::between(ilo, ihi);
  }
}
}  // namespace config_options

/// CONFIG, host -> device (acknowledged): the SLAM step's settings, generated from the option table
/// (core/options.h): one field per line, in the table's order, named as the option, its wire type
/// from the option's TYPE (config_options::WireTypes), its default the table's, its range the
/// table's (config_options::wire_range), its unit and note the table's. Then stats_period_scans, the
/// device's own. node/wire.hpp converts it to and from the library's settings. Domain checks only;
/// the device also checks its capacities (groups, node budget) and every option's range
/// (SlamStep::configure).
struct Config : Codec<Config> {
  static constexpr MsgType kType = MsgType::kConfig;
  static constexpr const char* kName = "CONFIG";
  static constexpr const char* kRule = "max_range_m>min_range_m";

#define GEOJCBB_CONFIG_MEMBER(TYPE, name, def, range, unit, cli, doc) \
  config_options::WireTypes::TYPE name = static_cast<config_options::WireTypes::TYPE>(def);
  GEOJCBB_OPTIONS(GEOJCBB_CONFIG_MEMBER)
#undef GEOJCBB_CONFIG_MEMBER

  /// The device sends STATS unasked after the POSE of every this-many scans since CONFIG or RESET
  /// (0: only on request).
  std::uint16_t stats_period_scans = 0;

  /// One field per line of the option table, in its order, then the device's own stats_period_scans.
  /// (One make_tuple: clang's constant evaluator gives up on a tuple_cat of 67 tuples.)
  // clang-format off
  static constexpr auto fields() {
#define GEOJCBB_CONFIG_RANGE(kind, lo, hi) config_options::Kind::k##kind, static_cast<double>(lo), static_cast<double>(hi)
#define GEOJCBB_CONFIG_FIELD(TYPE, name, def, range, unit, cli, doc) \
  field(#name, &Config::name, config_options::wire_range<config_options::WireTypes::TYPE>(GEOJCBB_CONFIG_RANGE range), \
        unit, doc),
    return std::make_tuple(
        GEOJCBB_OPTIONS(GEOJCBB_CONFIG_FIELD)
        field("stats_period_scans", &Config::stats_period_scans, range::any(), "scans",
              "0: STATS only on request; N > 0: the device also sends STATS, unasked, after the POSE of every "
              "N-th scan since this CONFIG or the last RESET"));
#undef GEOJCBB_CONFIG_FIELD
#undef GEOJCBB_CONFIG_RANGE
  }
  // clang-format on
  [[nodiscard]] Error rule() const { return max_range_m > min_range_m ? Error::kOk : Error::kOutOfRange; }
};

/// ACK: a control message (CONFIG, RESET, ...) was accepted.
struct Ack : Codec<Ack> {
  static constexpr MsgType kType = MsgType::kAck;
  static constexpr const char* kName = "ACK";

  std::uint8_t acked_type = 0;  ///< the MsgType of the accepted frame (not checked: a stray ACK matches nothing)
  std::uint16_t acked_seq = 0;

  static constexpr auto fields() {
    return std::make_tuple(field("acked_type", &Ack::acked_type, range::any(), "", "a stray ACK matches nothing"),
                           field("acked_seq", &Ack::acked_seq));
  }
};

/// NACK: a frame was refused; error says why (any type number, known or not).
struct Nack : Codec<Nack> {
  static constexpr MsgType kType = MsgType::kNack;
  static constexpr const char* kName = "NACK";

  std::uint8_t nacked_type = 0;
  std::uint16_t nacked_seq = 0;
  Error error = Error::kOutOfRange;  ///< kBadLength .. kInternal

  static constexpr auto fields() {
    return std::make_tuple(field("nacked_type", &Nack::nacked_type, range::any(), "", "including unknown types"),
                           field("nacked_seq", &Nack::nacked_seq),
                           field("error", &Nack::error, detail::reportable_error(), "", "an `Error`"));
  }
};

/// PING and PONG: link check; the device echoes the nonce.
template <MsgType Type>
struct NonceMsg : Codec<NonceMsg<Type>> {
  static constexpr MsgType kType = Type;
  static constexpr const char* kName = Type == MsgType::kPing ? "PING" : "PONG";

  std::uint32_t nonce = 0;

  static constexpr auto fields() { return std::make_tuple(field("nonce", &NonceMsg::nonce)); }
};
using Ping = NonceMsg<MsgType::kPing>;
using Pong = NonceMsg<MsgType::kPong>;

/// RESET, host -> device (acknowledged): restart the filter at this pose with an empty map.
struct Reset : Codec<Reset> {
  static constexpr MsgType kType = MsgType::kReset;
  static constexpr const char* kName = "RESET";
  static constexpr const char* kRule = "positive-definite";

  float x_m = 0.0f;  ///< world frame
  float y_m = 0.0f;
  float theta_rad = 0.0f;
  /// Pose covariance, upper triangle (p00, p01, p02, p11, p12, p22) over (x, y, theta); positive
  /// definite (symmetric by construction).
  std::array<float, 6> cov_upper{1e-6f, 0.0f, 0.0f, 1e-6f, 0.0f, 1e-6f};

  static constexpr auto fields() {
    return std::make_tuple(
        field("x_m", &Reset::x_m, range::finite(), "m", "world frame"), field("y_m", &Reset::y_m, range::finite(), "m"),
        field("theta_rad", &Reset::theta_rad, range::finite(), "rad"),
        field("cov_upper", &Reset::cov_upper, range::finite(), "",
              "P over (x, y, theta), symmetric by construction: positive definite", detail::kCovUpperNames));
  }
  [[nodiscard]] Error rule() const { return detail::spd3(cov_upper) ? Error::kOk : Error::kNotPositiveDefinite; }
};

/// RELOCALISE, host -> device (stream: ordered with ODOMETRY and OBS_BATCH, as ODOMETRY): the robot
/// was carried or its pose is known to be wrong. The pose covariance is re-set to cov_upper and its
/// correlation with the map dropped (the estimate and the map kept); with the relocaliser on
/// (CONFIG relocalise) the robot is then lost: each scan is aligned against the map until a pose is
/// accepted and confirmed.
struct Relocalise : Codec<Relocalise> {
  static constexpr MsgType kType = MsgType::kRelocalise;
  static constexpr const char* kName = "RELOCALISE";
  static constexpr const char* kRule = "positive-definite";

  /// Pose covariance, upper triangle (p00, p01, p02, p11, p12, p22) over (x, y, theta).
  std::array<float, 6> cov_upper{1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f};

  static constexpr auto fields() {
    return std::make_tuple(field("cov_upper", &Relocalise::cov_upper, range::finite(), "",
                                 "P over (x, y, theta), symmetric by construction: positive definite",
                                 detail::kCovUpperNames));
  }
  [[nodiscard]] Error rule() const { return detail::spd3(cov_upper) ? Error::kOk : Error::kNotPositiveDefinite; }
};

/// SHUTDOWN, host -> device (acknowledged, only after HELLO): the device answers ACK, then calls the
/// board's shutdown hook with exit_code (the desktop device exits with it; the Cortex-M4F port ends
/// QEMU through semihosting). A board without a hook only acknowledges.
struct Shutdown : Codec<Shutdown> {
  static constexpr MsgType kType = MsgType::kShutdown;
  static constexpr const char* kName = "SHUTDOWN";

  std::uint8_t exit_code = 0;  ///< any

  static constexpr auto fields() { return std::make_tuple(field("exit_code", &Shutdown::exit_code)); }
};

/// ODOMETRY, host -> device (stream): velocity command over dt and its noise.
struct Odometry : Codec<Odometry> {
  static constexpr MsgType kType = MsgType::kOdometry;
  static constexpr const char* kName = "ODOMETRY";

  float v_mps = 0.0f;          ///< forward speed, robot frame
  float w_radps = 0.0f;        ///< turn rate
  float dt_s = 0.0f;           ///< >= 0
  float sigma_v_mps = 0.0f;    ///< >= 0
  float sigma_w_radps = 0.0f;  ///< >= 0

  static constexpr auto fields() {
    return std::make_tuple(field("v_mps", &Odometry::v_mps, range::finite(), "m/s", "forward speed, robot frame"),
                           field("w_radps", &Odometry::w_radps, range::finite(), "rad/s", "turn rate"),
                           field("dt_s", &Odometry::dt_s, range::not_below(0.0f), "s"),
                           field("sigma_v_mps", &Odometry::sigma_v_mps, range::not_below(0.0f), "m/s"),
                           field("sigma_w_radps", &Odometry::sigma_w_radps, range::not_below(0.0f), "rad/s"));
  }
};

/// ODOM_DELTA, host -> device (stream), instead of ODOMETRY: a pose increment (wheel odometry, a
/// vehicle model) in the robot's frame at its start, with its covariance (positive semi-definite:
/// the filter refuses anything else, and the device answers ERROR invalid field).
struct OdomDelta : Codec<OdomDelta> {
  static constexpr MsgType kType = MsgType::kOdomDelta;
  static constexpr const char* kName = "ODOM_DELTA";

  float dx_m = 0.0f;        ///< forward
  float dy_m = 0.0f;        ///< to the left
  float dtheta_rad = 0.0f;  ///< counter-clockwise
  /// Covariance of (dx, dy, dtheta), upper triangle (c00, c01, c02, c11, c12, c22).
  std::array<float, 6> cov_upper{0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};

  static constexpr auto fields() {
    return std::make_tuple(field("dx_m", &OdomDelta::dx_m, range::finite(), "m", "forward, robot frame"),
                           field("dy_m", &OdomDelta::dy_m, range::finite(), "m", "to the left"),
                           field("dtheta_rad", &OdomDelta::dtheta_rad, range::finite(), "rad", "counter-clockwise"),
                           field("cov_upper", &OdomDelta::cov_upper, range::finite(), "",
                                 "covariance of (dx, dy, dtheta): positive semi-definite", detail::kCovUpperNames));
  }
};

/// One range-bearing observation with its measurement covariance R (symmetric positive definite).
struct ObservationWire {
  static constexpr const char* kRule = "positive-definite";

  float range_m = 0.0f;      ///< >= 0, robot frame
  float bearing_rad = 0.0f;  ///< [-pi, pi], robot frame
  float r00 = 1e-4f;         ///< R = [r00 r01; r01 r11], range then bearing
  float r01 = 0.0f;
  float r11 = 1e-4f;

  static constexpr auto fields() {
    return std::make_tuple(
        field("range_m", &ObservationWire::range_m, range::not_below(0.0f), "m", "robot frame"),
        field("bearing_rad", &ObservationWire::bearing_rad, range::interval(-kPiF, kPiF, false, false), "rad",
              "robot frame"),
        field("r00", &ObservationWire::r00, range::finite(), "m²", "R = [r00 r01; r01 r11] positive definite"),
        field("r01", &ObservationWire::r01, range::finite(), "m·rad"),
        field("r11", &ObservationWire::r11, range::finite(), "rad²"));
  }
  [[nodiscard]] Error rule() const { return detail::spd2(r00, r01, r11) ? Error::kOk : Error::kNotPositiveDefinite; }
};

/// OBS_BATCH, host -> device (stream): the observations of one scan.
/// @tparam MaxObs  capacity of the receiver (count on the wire is refused above it)
template <std::size_t MaxObs = kDefaultMaxObsPerBatch>
struct ObsBatchT : Codec<ObsBatchT<MaxObs>> {
  static constexpr MsgType kType = MsgType::kObsBatch;
  static constexpr const char* kName = "OBS_BATCH";

  std::uint32_t batch_id = 0;
  std::uint8_t count = 0;  ///< <= MaxObs
  std::array<ObservationWire, MaxObs> obs{};

  static constexpr auto fields() {
    return std::make_tuple(
        field("batch_id", &ObsBatchT::batch_id, range::any(), "", "echoed by ASSOC_RESULT and POSE"),
        list("count", &ObsBatchT::count, &ObsBatchT::obs, "obs",
             "≤ the receiver's `MaxObs` (`kCapacityExceeded`), and `len` = fixed + item size · count exactly "
             "(`kBadLength`)"));
  }
};
using ObsBatch = ObsBatchT<>;

/// Feature ids of ASSOC_RESULT besides map ids (>= 0); geojcbb::kNewFeature and kUnmatched
/// (node/wire.hpp static_asserts the agreement).
constexpr std::int32_t kFeatureNew = -1;        ///< the observation starts a new landmark
constexpr std::int32_t kFeatureUnmatched = -2;  ///< clutter, or ambiguous: not used

/// What became of an observation (firmware_lib node::Outcome, value for value; node/wire.hpp
/// static_asserts it).
enum class PairingOutcome : std::uint8_t {
  kPaired = 0,    ///< feature_id: the map landmark it was paired with
  kNewLandmark,   ///< no compatible candidate; feature_id: the landmark it became
  kNewDropped,    ///< no compatible candidate, inside the augmentation gate: dropped (kFeatureNew)
  kUnmatched,     ///< ambiguous, left unpaired (kFeatureUnmatched)
  kNotAugmented,  ///< would have become a landmark, map full (kFeatureNew)
  kMover,         ///< taken by a mover's track: neither paired nor mapped (kFeatureUnmatched)
};
constexpr std::uint8_t kMaxPairingOutcome = 5;

struct PairingWire {
  static constexpr const char* kRule = "feature_id>=0_iff_outcome_paired_or_new_landmark";

  PairingOutcome outcome = PairingOutcome::kUnmatched;
  std::int32_t feature_id = kFeatureUnmatched;  ///< >= 0, kFeatureNew or kFeatureUnmatched
  float d2 = 0.0f;  ///< Mahalanobis distance squared of the pairing: finite >= 0, or +inf (no candidate)

  static constexpr auto fields() {
    return std::make_tuple(
        field("outcome", &PairingWire::outcome, range::between(0, kMaxPairingOutcome), "",
              "0 paired, 1 new landmark, 2 new but dropped (inside the augmentation gate), 3 unmatched "
              "(ambiguous), 4 not augmented (map full), 5 a mover's (taken by a mover track)"),
        field("feature_id", &PairingWire::feature_id, range::at_least(kFeatureUnmatched), "",
              "outcomes 0 and 1: ≥ 0, the landmark paired with / created (ids are stable); otherwise −1 NEW "
              "(`kFeatureNew`) or −2 UNMATCHED (`kFeatureUnmatched`)"),
        field("d2", &PairingWire::d2, range::or_plus_inf(range::not_below(0.0f)), "",
              "Mahalanobis distance squared; +Inf: no candidate; NaN and −Inf rejected"));
  }
  [[nodiscard]] Error rule() const {
    const bool has_id = outcome == PairingOutcome::kPaired || outcome == PairingOutcome::kNewLandmark;
    return has_id == (feature_id >= 0) ? Error::kOk : Error::kOutOfRange;
  }
};

/// ASSOC_RESULT, device -> host: per observation of the batch, in order, its feature.
template <std::size_t MaxObs = kDefaultMaxObsPerBatch>
struct AssocResultT : Codec<AssocResultT<MaxObs>> {
  static constexpr MsgType kType = MsgType::kAssocResult;
  static constexpr const char* kName = "ASSOC_RESULT";

  std::uint32_t batch_id = 0;
  std::uint8_t count = 0;  ///< <= MaxObs
  std::array<PairingWire, MaxObs> pairs{};

  static constexpr auto fields() {
    return std::make_tuple(
        field("batch_id", &AssocResultT::batch_id, range::any(), "", "the OBS_BATCH's or SUBMAP_SEED's"),
        list("count", &AssocResultT::count, &AssocResultT::pairs, "pairs",
             "≤ `MaxObs`, and `len` = fixed + item size · count exactly"));
  }
};
using AssocResult = AssocResultT<>;

/// A landmark a scan removed (POSE's list).
struct RemovedWire {
  std::int32_t feature_id = 0;

  static constexpr auto fields() {
    return std::make_tuple(field("feature_id", &RemovedWire::feature_id, range::at_least(0), "",
                                 "the id of a landmark this scan removed (ids are never reused)"));
  }
};

/// Removed landmarks' ids per POSE: more removed in one scan are counted (`removed`), not named.
constexpr std::size_t kRemovedPerPose = 8;

/// POSE, device -> host: the filter's pose after a batch. The covariance is what the filter holds:
/// finite with a non-negative diagonal (the host judges consistency, for example NEES, itself).
/// The landmarks the scan removed (by their evidence, a merge, an eviction): how many, and the first
/// kRemovedPerPose ids, so the host knows what the local map still holds (docs/submaps.md, the seed).
struct Pose : Codec<Pose> {
  static constexpr MsgType kType = MsgType::kPose;
  static constexpr const char* kName = "POSE";
  static constexpr const char* kRule = "diagonal>=0,count=min(removed,8)";

  std::uint32_t batch_id = 0;
  float x_m = 0.0f;  ///< world frame
  float y_m = 0.0f;
  float theta_rad = 0.0f;
  std::array<float, 6> cov_upper{};  ///< (p00, p01, p02, p11, p12, p22) over (x, y, theta)
  std::uint16_t landmark_count = 0;
  /// 0, or this scan closed the local map: this many SUBMAP and SUBMAP_COV frames follow, and the
  /// device takes no stream frame (ERROR kBusy) until SUBMAP_ACK.
  std::uint16_t submap_frames = 0;
  std::uint16_t removed = 0;  ///< landmarks this scan removed (saturating)
  std::uint8_t count = 0;     ///< of them, named in ids: min(removed, kRemovedPerPose)
  std::array<RemovedWire, kRemovedPerPose> ids{};

  static constexpr auto fields() {
    return std::make_tuple(
        field("batch_id", &Pose::batch_id), field("x_m", &Pose::x_m, range::finite(), "m", "world frame"),
        field("y_m", &Pose::y_m, range::finite(), "m"), field("theta_rad", &Pose::theta_rad, range::finite(), "rad"),
        field("cov_upper", &Pose::cov_upper, range::finite(), "",
              "diagonal ≥ 0: the pose reports what the filter holds, the host judges its "
              "consistency",
              detail::kCovUpperNames),
        field("landmark_count", &Pose::landmark_count),
        field("submap_frames", &Pose::submap_frames, range::any(), "frames",
              "0, or the local map closed with this scan: this many SUBMAP and SUBMAP_COV frames follow, and "
              "stream frames get ERROR `kBusy` until SUBMAP_ACK"),
        field("removed", &Pose::removed, range::any(), "",
              "landmarks this scan removed (by their evidence, a merge or an eviction), saturating"),
        list("count", &Pose::count, &Pose::ids, "ids", "min(`removed`, 8): the first removed landmarks' ids"));
  }
  [[nodiscard]] Error rule() const {
    const bool diagonal = cov_upper[0] >= 0.0f && cov_upper[3] >= 0.0f && cov_upper[5] >= 0.0f;
    const std::size_t named = removed < kRemovedPerPose ? removed : kRemovedPerPose;
    return diagonal && count == named ? Error::kOk : Error::kOutOfRange;
  }
};

// A local map's hand-over (docs/submaps.md). A map with n landmarks and state dimension
// D = 3 + 2n travels as ceil(max(n, 1) / kSubmapLandmarksPerFrame) SUBMAP frames (chunks 0, 1, ...)
// then ceil(D (D + 1) / 2 / kSubmapCovPerFrame) SUBMAP_COV frames (the following chunks): the
// covariance's upper triangle column by column, (0,0), (0,1), (1,1), (0,2), ..., as the device
// stores it, read in place. The map's frame is the robot's pose when the map began, which is the
// previous map's last robot pose (its state's first three and their covariance): the base pose.

/// Landmarks per SUBMAP frame, and covariance entries per SUBMAP_COV frame: each message's struct
/// (the device builds one at a time on its stack) stays within the 512-byte frame limit of the
/// firmware's stack check (docs/firmware.md), 348 and 400 bytes (SUBMAP's landmark is 20 bytes in
/// the struct, 18 on the wire).
constexpr std::size_t kSubmapLandmarksPerFrame = 16;
constexpr std::size_t kSubmapCovPerFrame = 96;

/// The frames of a hand-over of a map with `landmarks` landmarks.
constexpr std::uint32_t submap_landmark_frames(std::uint32_t landmarks) {
  return landmarks == 0 ? 1u
                        : (landmarks + static_cast<std::uint32_t>(kSubmapLandmarksPerFrame) - 1) /
                              static_cast<std::uint32_t>(kSubmapLandmarksPerFrame);
}
constexpr std::uint32_t submap_cov_entries(std::uint32_t landmarks) {
  const std::uint32_t d = 3 + 2 * landmarks;
  return d * (d + 1) / 2;
}
constexpr std::uint32_t submap_frames(std::uint32_t landmarks) {
  return submap_landmark_frames(landmarks) +
         (submap_cov_entries(landmarks) + static_cast<std::uint32_t>(kSubmapCovPerFrame) - 1) /
             static_cast<std::uint32_t>(kSubmapCovPerFrame);
}

struct SubmapLandmarkWire {
  std::int32_t id = 0;  ///< the landmark's id (ids go on across maps; a carried landmark keeps its id)
  float x_m = 0.0f;     ///< in the map's frame
  float y_m = 0.0f;
  bool confirmed = false;  ///< by its evidence; a tentative one joins only when paired
  /// Kept into the next map (the restart's carry): one the next map no longer holds when it is handed
  /// over was removed there by its evidence, and leaves the global map.
  bool carried = false;
  float exist_nats = 0.0f;  ///< its log-odds of existence (ekf::LandmarkPolicy): the global map keeps it

  static constexpr auto fields() {
    return std::make_tuple(
        field("id", &SubmapLandmarkWire::id, range::at_least(0), "", "stable across maps"),
        field("x_m", &SubmapLandmarkWire::x_m, range::finite(), "m", "the map's frame"),
        field("y_m", &SubmapLandmarkWire::y_m, range::finite(), "m"),
        field("confirmed", &SubmapLandmarkWire::confirmed, range::one_of(0, 1)),
        field("carried", &SubmapLandmarkWire::carried, range::one_of(0, 1), "", "kept into the next map"),
        field("exist_nats", &SubmapLandmarkWire::exist_nats, range::finite(), "nats", "log-odds of existence"));
  }
};

/// SUBMAP, device -> host: a closed local map, its header and landmarks [first, first + count).
struct Submap : Codec<Submap> {
  static constexpr MsgType kType = MsgType::kSubmap;
  static constexpr const char* kName = "SUBMAP";
  static constexpr const char* kRule = "chunk<chunks,first+count<=landmarks";

  std::uint32_t map_id = 0;     ///< 0, 1, ... since RESET
  std::uint16_t chunk = 0;      ///< this frame's index in the hand-over
  std::uint16_t chunks = 2;     ///< the hand-over's frames (SUBMAP and SUBMAP_COV): at least 2
  std::uint16_t landmarks = 0;  ///< n, the map's landmarks
  std::uint16_t first = 0;      ///< the index of this frame's first landmark
  float x_m = 0.0f;             ///< the robot's last pose in the map's frame (the state's first three)
  float y_m = 0.0f;
  float theta_rad = 0.0f;
  std::uint8_t count = 0;  ///< <= kSubmapLandmarksPerFrame
  std::array<SubmapLandmarkWire, kSubmapLandmarksPerFrame> items{};

  static constexpr auto fields() {
    return std::make_tuple(
        field("map_id", &Submap::map_id, range::any(), "", "0, 1, ... since RESET"),
        field("chunk", &Submap::chunk, range::any(), "", "< `chunks`"),
        field("chunks", &Submap::chunks, range::at_least(2), "frames", "SUBMAP and SUBMAP_COV frames of the map"),
        field("landmarks", &Submap::landmarks, range::any(), "", "n"),
        field("first", &Submap::first, range::any(), "", "`first` + `count` ≤ `landmarks`"),
        field("x_m", &Submap::x_m, range::finite(), "m", "the robot's last pose, the map's frame"),
        field("y_m", &Submap::y_m, range::finite(), "m"),
        field("theta_rad", &Submap::theta_rad, range::finite(), "rad"),
        list("count", &Submap::count, &Submap::items, "landmarks",
             "≤ 16, and `len` = fixed + item size · count exactly"));
  }
  [[nodiscard]] Error rule() const {
    return chunk < chunks && static_cast<std::uint32_t>(first) + count <= landmarks ? Error::kOk : Error::kOutOfRange;
  }
};

struct CovEntryWire {
  float v = 0.0f;
  static constexpr auto fields() { return std::make_tuple(field("v", &CovEntryWire::v, range::finite())); }
};

/// SUBMAP_COV, device -> host: entries [offset, offset + count) of the map's covariance (upper
/// triangle, column by column).
struct SubmapCov : Codec<SubmapCov> {
  static constexpr MsgType kType = MsgType::kSubmapCov;
  static constexpr const char* kName = "SUBMAP_COV";
  static constexpr const char* kRule = "chunk<chunks";

  std::uint32_t map_id = 0;
  std::uint16_t chunk = 0;
  std::uint16_t chunks = 2;
  std::uint32_t offset = 0;  ///< the first entry's index in the packed upper triangle
  std::uint8_t count = 0;    ///< <= kSubmapCovPerFrame
  std::array<CovEntryWire, kSubmapCovPerFrame> items{};

  static constexpr auto fields() {
    return std::make_tuple(field("map_id", &SubmapCov::map_id),
                           field("chunk", &SubmapCov::chunk, range::any(), "", "< `chunks`"),
                           field("chunks", &SubmapCov::chunks, range::at_least(2), "frames"),
                           field("offset", &SubmapCov::offset, range::any(), "",
                                 "of the first entry: column c's row r (r ≤ c) is c (c + 1) / 2 + r"),
                           list("count", &SubmapCov::count, &SubmapCov::items, "entries",
                                "≤ 96, and `len` = fixed + item size · count exactly"));
  }
  [[nodiscard]] Error rule() const { return chunk < chunks ? Error::kOk : Error::kOutOfRange; }
};

/// SUBMAP_ACK, host -> device (acknowledged): map `map_id` arrived whole (the device ACKs and starts
/// the next map), or, with send, send it (the device ACKs, then sends): again from the same memory
/// while it is pending (frames lost, a reconnection), or, for the current map, closed now (the end of
/// a run).
struct SubmapAck : Codec<SubmapAck> {
  static constexpr MsgType kType = MsgType::kSubmapAck;
  static constexpr const char* kName = "SUBMAP_ACK";

  std::uint32_t map_id = 0;
  bool send = false;

  static constexpr auto fields() {
    return std::make_tuple(field("map_id", &SubmapAck::map_id, range::any(), "",
                                 "the pending (or current) map's; the last map's again: ACK; else NACK `kOutOfRange`"),
                           field("send", &SubmapAck::send, range::one_of(0, 1), "",
                                 "1: send the map (again while pending; the current one: closed now)"));
  }
};

/// Seeds per SUBMAP_SEED frame: a place seen before enters the local map a few landmarks a scan
/// (the struct, which the device decodes on its stack, is 204 bytes).
constexpr std::size_t kSeedsPerFrame = 8;

struct SeedWire {
  static constexpr const char* kRule = "positive-definite";

  float x_m = 0.0f;  ///< in the local map's frame
  float y_m = 0.0f;
  float p00 = 1.0f;  ///< its covariance there [p00 p01; p01 p11]: the global map's marginal
  float p01 = 0.0f;
  float p11 = 1.0f;
  float exist_nats = 0.0f;  ///< its log-odds of existence in the global map (the device caps it at its saturation)

  static constexpr auto fields() {
    return std::make_tuple(field("x_m", &SeedWire::x_m, range::finite(), "m", "the local map's frame"),
                           field("y_m", &SeedWire::y_m, range::finite(), "m"),
                           field("p00", &SeedWire::p00, range::finite(), "m²", "[p00 p01; p01 p11] positive definite"),
                           field("p01", &SeedWire::p01, range::finite(), "m²"),
                           field("p11", &SeedWire::p11, range::finite(), "m²"),
                           field("exist_nats", &SeedWire::exist_nats, range::finite(), "nats",
                                 "the global map's log-odds of existence; at most the device's saturation"));
  }
  [[nodiscard]] Error rule() const { return detail::spd2(p00, p01, p11) ? Error::kOk : Error::kNotPositiveDefinite; }
};

/// SUBMAP_SEED, host -> device (stream, between scans): landmarks of the global map near the robot
/// that the current local map does not hold (docs/submaps.md, "Seed"), in its frame, each with its
/// marginal covariance (uncorrelated with the map and with each other). The device answers
/// ASSOC_RESULT with this batch_id, one pairing per seed in order: kNewLandmark (seeded, the id it
/// took), kUnmatched (a landmark the map holds is compatible with it, d2 the distance: the join pairs
/// them) or kNotAugmented (no room: the map's closing size or its capacity less a scan). A
/// retransmission is answered again, not applied twice.
struct SubmapSeed : Codec<SubmapSeed> {
  static constexpr MsgType kType = MsgType::kSubmapSeed;
  static constexpr const char* kName = "SUBMAP_SEED";

  std::uint32_t batch_id = 0;  ///< echoed by ASSOC_RESULT (the host numbers seeds and batches alike)
  std::uint32_t map_id = 0;    ///< the current local map's (another: ERROR kOutOfRange, nothing seeded)
  std::uint8_t count = 0;      ///< <= kSeedsPerFrame
  std::array<SeedWire, kSeedsPerFrame> items{};

  static constexpr auto fields() {
    return std::make_tuple(field("batch_id", &SubmapSeed::batch_id, range::any(), "", "echoed by ASSOC_RESULT"),
                           field("map_id", &SubmapSeed::map_id, range::any(), "", "the current local map's"),
                           list("count", &SubmapSeed::count, &SubmapSeed::items, "seeds",
                                "≤ 8, and `len` = fixed + item size · count exactly"));
  }
};

/// STATS_REQUEST, host -> device: empty payload; the device answers STATS.
struct StatsRequest : Codec<StatsRequest> {
  static constexpr MsgType kType = MsgType::kStatsRequest;
  static constexpr const char* kName = "STATS_REQUEST";

  static constexpr auto fields() { return std::tuple<>(); }
};

/// STATS, device -> host: link counters (Decoder and message layer), pipeline counters, and the
/// instruction counts (DWT CYCCNT or QEMU icount) of the last scan by stage.
struct Stats : Codec<Stats> {
  static constexpr MsgType kType = MsgType::kStats;
  static constexpr const char* kName = "STATS";

  std::uint32_t frames_ok = 0;
  std::uint32_t bad_crc = 0;
  std::uint32_t bad_length = 0;
  std::uint32_t overrun = 0;
  std::uint32_t unknown_type = 0;
  std::uint32_t bad_version = 0;
  std::uint32_t bad_flags = 0;
  std::uint32_t invalid_field = 0;    ///< frames whose payload failed validation
  std::uint32_t budget_hits = 0;      ///< scans that ran out of the JCBB node budget
  std::uint32_t ambiguous_scans = 0;  ///< scans whose alignment had distinct poses within the margin
  std::uint32_t movers = 0;           ///< landmarks that became movers (the world model's motion test)
  std::uint32_t scans = 0;            ///< scans processed
  std::uint32_t instr_predict = 0;
  // The last scan's step by stage: one field per row of the stage table (stage_counts.h).
#define GEOJCBB_STATS_STAGE_MEMBER(name, meaning) std::uint32_t instr_##name = 0;
  GEOJCBB_STAGE_COUNTS(GEOJCBB_STATS_STAGE_MEMBER)
#undef GEOJCBB_STATS_STAGE_MEMBER
  std::uint32_t stack_high_water_bytes = 0;

  static constexpr auto fields() {
    constexpr const char* kInstr = "instructions";
    return std::make_tuple(
        field("frames_ok", &Stats::frames_ok, range::any(), "frames", "`Decoder` counter"),
        field("bad_crc", &Stats::bad_crc, range::any(), "frames", "`Decoder` counter"),
        field("bad_length", &Stats::bad_length, range::any(), "frames", "`Decoder` counter"),
        field("overrun", &Stats::overrun, range::any(), "frames", "`Decoder` counter"),
        field("unknown_type", &Stats::unknown_type, range::any(), "frames", "`MessageCounters` counter"),
        field("bad_version", &Stats::bad_version, range::any(), "frames", "`Decoder` counter"),
        field("bad_flags", &Stats::bad_flags, range::any(), "frames", "`Decoder` counter"),
        field("invalid_field", &Stats::invalid_field, range::any(), "frames",
              "`MessageCounters`: payloads that failed validation"),
        field("budget_hits", &Stats::budget_hits, range::any(), "scans", "scans that ran out of JCBB nodes"),
        field("ambiguous_scans", &Stats::ambiguous_scans, range::any(), "scans",
              "the relocaliser's or loop check's alignment had distinct poses within the margin: nothing committed"),
        field("movers", &Stats::movers, range::any(), "landmarks",
              "landmarks that failed the motion test (or the static gate with it) and became movers"),
        field("scans", &Stats::scans, range::any(), "scans", "scans processed"),
        field("instr_predict", &Stats::instr_predict, range::any(), kInstr, "the last odometry's prediction"),
#define GEOJCBB_STATS_STAGE_FIELD(name, meaning) \
  field("instr_" #name, &Stats::instr_##name, range::any(), kInstr, meaning),
        GEOJCBB_STAGE_COUNTS(GEOJCBB_STATS_STAGE_FIELD)
#undef GEOJCBB_STATS_STAGE_FIELD
            field("stack_high_water_bytes", &Stats::stack_high_water_bytes, range::any(), "B",
                  "0 where the board does not measure it"));
  }
};

/// ERROR, device -> host: a frame was refused where no NACK applies (a stream message, or a frame
/// the device could not attribute), or the pipeline failed.
struct ErrorReport : Codec<ErrorReport> {
  static constexpr MsgType kType = MsgType::kError;
  static constexpr const char* kName = "ERROR";

  Error error = Error::kInternal;  ///< kBadLength .. kInternal
  std::uint8_t offending_type = 0;
  std::uint16_t offending_seq = 0;

  static constexpr auto fields() {
    return std::make_tuple(field("error", &ErrorReport::error, detail::reportable_error(), "", "an `Error`"),
                           field("offending_type", &ErrorReport::offending_type),
                           field("offending_seq", &ErrorReport::offending_seq));
  }
};

// ---------------------------------------------------------------------------------------------
// Every message of the schema, in schema order; MaxObs: the lists' capacity on this side.

template <class... M>
struct MessageList {
  static constexpr std::size_t kSize = sizeof...(M);
};
template <std::size_t MaxObs = kDefaultMaxObsPerBatch>
using AllMessages = MessageList<Hello, Capabilities, Config, Ack, Nack, Ping, Pong, Reset, Shutdown, Relocalise,
                                SubmapAck, Odometry, OdomDelta, ObsBatchT<MaxObs>, SubmapSeed, AssocResultT<MaxObs>,
                                Pose, Submap, SubmapCov, StatsRequest, Stats, ErrorReport>;

namespace detail {
template <class... M>
constexpr std::array<MsgType, sizeof...(M)> types_of(MessageList<M...>) {
  return {M::kType...};
}
template <class... M>
constexpr std::array<const char*, sizeof...(M)> names_of(MessageList<M...>) {
  return {M::kName...};
}
template <std::size_t N, class... M>
constexpr FixedText<N> schema_text_of(MessageList<M...>) {
  FixedText<N> t{};
  t.put(kSchemaPrologue);
  (render_message_line<M>(t), ...);
  return t;
}
/// Capacity of the text buffer: the text's length (+ the NUL), found by a first rendering.
constexpr std::size_t kSchemaTextCapacity = schema_text_of<8192>(AllMessages<>{}).size + 1;
}  // namespace detail

constexpr std::array<MsgType, AllMessages<>::kSize> kAllMsgTypes = detail::types_of(AllMessages<>{});

/// True when t is a type number of this schema.
constexpr bool is_known_type(std::uint8_t t) {
  for (const MsgType k : kAllMsgTypes) {  // <= 22
    if (static_cast<std::uint8_t>(k) == t) return true;
  }
  return false;
}

constexpr const char* to_string(MsgType t) {
  constexpr auto kNames = detail::names_of(AllMessages<>{});
  for (std::size_t i = 0; i < kAllMsgTypes.size(); ++i) {  // <= 22
    if (kAllMsgTypes[i] == t) return kNames[i];
  }
  return "?";
}

/// The schema text: kSchemaPrologue, then one "msg" line per message rendered from its fields().
inline constexpr FixedText<detail::kSchemaTextCapacity> kSchemaTextBuffer =
    detail::schema_text_of<detail::kSchemaTextCapacity>(AllMessages<>{});
static_assert(!kSchemaTextBuffer.overflow);
inline constexpr const char* kSchemaText = kSchemaTextBuffer.data.data();
inline constexpr std::size_t kSchemaTextLength = kSchemaTextBuffer.size;  ///< without the NUL

/// FNV-1a 32 of kSchemaText: names, types, order and ranges of every field of every message.
inline constexpr std::uint32_t kSchemaHash = fnv1a32(kSchemaText, kSchemaTextLength);
constexpr std::uint32_t current_schema_hash() { return kSchemaHash; }

/// Whether a device accepts a HELLO. @return kOk; kBadVersion; kSchemaMismatch.
[[nodiscard]] constexpr Error check_hello(std::uint8_t protocol_version, std::uint32_t schema_hash) {
  if (protocol_version != kProtocolVersion) return Error::kBadVersion;
  if (schema_hash != kSchemaHash) return Error::kSchemaMismatch;
  return Error::kOk;
}
[[nodiscard]] constexpr Error check_hello(const Hello& h) { return check_hello(h.protocol_version, h.schema_hash); }

/// Parses kSchemaText for message `type`.
constexpr SchemaLayout schema_layout(std::uint8_t type) { return schema_layout(kSchemaText, kSchemaTextLength, type); }

// The rendered text states every layout the codec writes (a cross-check of the renderer).
namespace detail {
template <class... M>
constexpr bool all_match_schema(MessageList<M...>) {
  return ((schema_layout(static_cast<std::uint8_t>(M::kType)).found &&
           schema_layout(static_cast<std::uint8_t>(M::kType)).fixed_bytes == M::kFixedSize &&
           schema_layout(static_cast<std::uint8_t>(M::kType)).item_bytes == M::kItemSize) &&
          ...);
}
}  // namespace detail
static_assert(detail::all_match_schema(AllMessages<>{}));
static_assert(!schema_layout(0x00).found && !schema_layout(0xFF).found);
static_assert(Hello::kPayloadSize == 5 && Capabilities::kPayloadSize == 37 && Config::kPayloadSize == 170 &&
                  Reset::kPayloadSize == 36 && Relocalise::kPayloadSize == 24 && Odometry::kPayloadSize == 20 &&
                  OdomDelta::kPayloadSize == 36 && Pose::kFixedSize == 47 && Pose::kItemSize == 4 &&
                  Stats::kPayloadSize == 100 && ObsBatch::kFixedSize == 5 && ObsBatch::kItemSize == 20 &&
                  AssocResult::kFixedSize == 5 && AssocResult::kItemSize == 9 && Submap::kFixedSize == 25 &&
                  Submap::kItemSize == 18 && SubmapCov::kFixedSize == 13 && SubmapCov::kItemSize == 4 &&
                  SubmapAck::kPayloadSize == 5 && SubmapSeed::kFixedSize == 9 && SubmapSeed::kItemSize == 24,
              "payload sizes of version 1 (docs/protocol.md)");

}  // namespace geojcbb::proto
