// protocol: the messages. Each is a plain struct with validate(), encode(payload buffer) and
// decode(payload bytes); fields are written one by one in little-endian order (wire.hpp), never by
// copying the struct. Inputs: payload bytes from the wire (untrusted). Outputs: a struct whose every
// field passed validation, or an Error with the struct untouched. Bounds: counted lists hold at most
// MaxObs items (a template parameter, default kDefaultMaxObsPerBatch), checked against kMaxPayload
// at compile time. Layouts, type numbers and ranges are the ones kSchemaText states (schema.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "geojcbb/protocol/error.hpp"
#include "geojcbb/protocol/frame.hpp"
#include "geojcbb/protocol/schema.hpp"
#include "geojcbb/protocol/wire.hpp"

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
  kOdometry = 0x10,      ///< host -> device, stream
  kObsBatch = 0x11,      ///< host -> device, stream
  kAssocResult = 0x20,   ///< device -> host
  kPose = 0x21,          ///< device -> host
  kStatsRequest = 0x30,  ///< host -> device
  kStats = 0x31,         ///< device -> host
  kError = 0x7F,         ///< device -> host
};

constexpr std::array<MsgType, 16> kAllMsgTypes = {
    MsgType::kHello,    MsgType::kCapabilities, MsgType::kConfig,   MsgType::kAck,
    MsgType::kNack,     MsgType::kPing,         MsgType::kPong,     MsgType::kReset,
    MsgType::kShutdown, MsgType::kOdometry,     MsgType::kObsBatch, MsgType::kAssocResult,
    MsgType::kPose,     MsgType::kStatsRequest, MsgType::kStats,    MsgType::kError};

/// True when t is a type number of this schema.
constexpr bool is_known_type(std::uint8_t t) {
  for (const MsgType k : kAllMsgTypes) {  // <= 16
    if (static_cast<std::uint8_t>(k) == t) return true;
  }
  return false;
}

constexpr const char* to_string(MsgType t) {
  switch (t) {
    case MsgType::kHello: return "HELLO";
    case MsgType::kCapabilities: return "CAPABILITIES";
    case MsgType::kConfig: return "CONFIG";
    case MsgType::kAck: return "ACK";
    case MsgType::kNack: return "NACK";
    case MsgType::kPing: return "PING";
    case MsgType::kPong: return "PONG";
    case MsgType::kReset: return "RESET";
    case MsgType::kShutdown: return "SHUTDOWN";
    case MsgType::kOdometry: return "ODOMETRY";
    case MsgType::kObsBatch: return "OBS_BATCH";
    case MsgType::kAssocResult: return "ASSOC_RESULT";
    case MsgType::kPose: return "POSE";
    case MsgType::kStatsRequest: return "STATS_REQUEST";
    case MsgType::kStats: return "STATS";
    case MsgType::kError: return "ERROR";
  }
  return "?";
}

/// Observations per OBS_BATCH (and pairings per ASSOC_RESULT) by default: DefaultBounds' 24.
constexpr std::size_t kDefaultMaxObsPerBatch = 24;
/// pi rounded to float (3.14159274f, a little above pi): the bound of bearings and fields of view.
constexpr float kPiF = 3.14159265358979323846f;

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
inline bool all_finite(const float* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {  // <= n
    if (!is_finite(v[i])) return false;
  }
  return true;
}
/// A code a NACK or ERROR may carry: a real error (not kOk, not kIncomplete) of this schema.
constexpr bool is_reportable(Error e) {
  const auto v = static_cast<std::uint8_t>(e);
  return v >= static_cast<std::uint8_t>(Error::kBadLength) && v < kErrorCount;
}
inline void write_cov(Writer& w, const std::array<float, 6>& c) {
  for (const float v : c) w.f32(v);  // 6
}
inline void read_cov(Reader& r, std::array<float, 6>& c) {
  for (float& v : c) v = r.f32();  // 6
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// Shared encode/decode. A message type M provides: kType, kMaxPayloadSize, validate(),
// payload_size(), write(Writer&), and read(const uint8_t*, size_t) that checks the payload length
// and fills the fields (validation comes after, in decode_payload).

/// Validates m and writes its payload into [out, out + cap).
/// @return kOk with len set; m's validation error; kBufferTooSmall. len is untouched on error.
template <class M>
[[nodiscard]] Error encode_payload(const M& m, std::uint8_t* out, std::size_t cap, std::size_t& len) {
  const Error e = m.validate();
  if (e != Error::kOk) return e;
  const std::size_t n = m.payload_size();
  if (n > cap || (out == nullptr && n > 0)) return Error::kBufferTooSmall;
  Writer w(out, cap);
  m.write(w);
  if (!w.ok() || w.size() != n) return Error::kInternal;  // write() disagrees with payload_size()
  len = n;
  return Error::kOk;
}

/// Reads and validates a payload into out; out is assigned only when everything passed.
/// @return kOk; kBadLength; kCapacityExceeded; kNonFinite; kOutOfRange; kNotPositiveDefinite.
template <class M>
[[nodiscard]] Error decode_payload(const std::uint8_t* p, std::size_t n, M& out) {
  if (p == nullptr && n > 0) return Error::kBadLength;
  M tmp{};
  Error e = tmp.read(p, n);
  if (e != Error::kOk) return e;
  e = tmp.validate();
  if (e != Error::kOk) return e;
  out = tmp;
  return Error::kOk;
}

/// Member encode/decode for every message (CRTP; the messages stay aggregates). A value-initialised
/// message of every type is valid (the fuzz target relies on it).
template <class M>
struct Codec {
  /// @return as encode_payload
  [[nodiscard]] Error encode(std::uint8_t* out, std::size_t cap, std::size_t& len) const {
    return encode_payload(static_cast<const M&>(*this), out, cap, len);
  }
  template <std::size_t N>
  [[nodiscard]] Error encode(std::array<std::uint8_t, N>& out, std::size_t& len) const {
    return encode_payload(static_cast<const M&>(*this), out.data(), N, len);
  }
  /// @return as decode_payload; *this is untouched on error
  [[nodiscard]] Error decode(const std::uint8_t* p, std::size_t n) {
    return decode_payload(p, n, static_cast<M&>(*this));
  }
};

// ---------------------------------------------------------------------------------------------

/// HELLO, host -> device: opens a session. The device answers CAPABILITIES, or NACK with
/// kBadVersion / kSchemaMismatch (see check_hello).
struct Hello : Codec<Hello> {
  static constexpr MsgType kType = MsgType::kHello;
  static constexpr std::size_t kPayloadSize = 5;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint8_t protocol_version = kProtocolVersion;
  std::uint32_t schema_hash = kSchemaHash;

  [[nodiscard]] Error validate() const { return Error::kOk; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.u8(protocol_version);
    w.u32(schema_hash);
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    protocol_version = r.u8();
    schema_hash = r.u32();
    return Error::kOk;
  }
};

/// Whether a device accepts a HELLO. @return kOk; kBadVersion; kSchemaMismatch.
[[nodiscard]] constexpr Error check_hello(std::uint8_t protocol_version, std::uint32_t schema_hash) {
  if (protocol_version != kProtocolVersion) return Error::kBadVersion;
  if (schema_hash != kSchemaHash) return Error::kSchemaMismatch;
  return Error::kOk;
}
[[nodiscard]] constexpr Error check_hello(const Hello& h) {
  return check_hello(h.protocol_version, h.schema_hash);
}

/// CAPABILITIES, device -> host: the device's compile-time bounds and identity.
struct Capabilities : Codec<Capabilities> {
  static constexpr MsgType kType = MsgType::kCapabilities;
  static constexpr std::size_t kFirmwareIdSize = 16;
  static constexpr std::size_t kPayloadSize = 21 + kFirmwareIdSize;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint8_t protocol_version = kProtocolVersion;
  std::uint32_t schema_hash = kSchemaHash;
  std::uint16_t max_observations = 1;  ///< per scan (M)
  std::uint16_t max_candidates = 1;    ///< map features offered to one association
  std::uint8_t max_groups = 1;
  std::uint16_t max_landmarks = 1;
  std::uint32_t max_jcbb_nodes = 1;    ///< per scan
  std::uint8_t scalar_bytes = 4;       ///< 4: float, 8: double
  std::uint32_t boot_id = 0;           ///< changes at every boot (a host sees a reset)
  std::array<char, kFirmwareIdSize> firmware_id{};  ///< printable ASCII, zero padded

  /// Copies text into firmware_id (truncated to 16 bytes, zero padded).
  void set_firmware_id(const char* text) {
    firmware_id.fill('\0');
    for (std::size_t i = 0; text != nullptr && i < kFirmwareIdSize && text[i] != '\0'; ++i) {  // <= 16
      firmware_id[i] = text[i];
    }
  }

  [[nodiscard]] Error validate() const {
    if (max_observations < 1 || max_candidates < 1 || max_groups < 1 || max_landmarks < 1 ||
        max_jcbb_nodes < 1 || (scalar_bytes != 4 && scalar_bytes != 8)) {
      return Error::kOutOfRange;
    }
    bool padding = false;
    for (const char c : firmware_id) {  // 16
      if (c == '\0') {
        padding = true;
      } else if (padding || c < 0x20 || c > 0x7E) {
        return Error::kOutOfRange;
      }
    }
    return Error::kOk;
  }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.u8(protocol_version);
    w.u32(schema_hash);
    w.u16(max_observations);
    w.u16(max_candidates);
    w.u8(max_groups);
    w.u16(max_landmarks);
    w.u32(max_jcbb_nodes);
    w.u8(scalar_bytes);
    w.u32(boot_id);
    for (const char c : firmware_id) w.u8(static_cast<std::uint8_t>(c));  // 16
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    protocol_version = r.u8();
    schema_hash = r.u32();
    max_observations = r.u16();
    max_candidates = r.u16();
    max_groups = r.u8();
    max_landmarks = r.u16();
    max_jcbb_nodes = r.u32();
    scalar_bytes = r.u8();
    boot_id = r.u32();
    for (char& c : firmware_id) c = static_cast<char>(r.u8());  // 16
    return Error::kOk;
  }
};

/// Strategy numbers of CONFIG (the same order as geojcbb::Strategy).
enum class StrategyCode : std::uint8_t { kIcnn = 0, kJcbb = 1, kKjcbb = 2, kDfjcbb = 3, kGemjcbb = 4, kGeojcbb = 5 };
constexpr std::uint8_t kStrategyCodeCount = 6;

/// CONFIG, host -> device (acknowledged): association strategy, gates, sensor model and landmark
/// policy. Domain checks only; the device also checks its capacities (groups, node budget).
struct Config : Codec<Config> {
  static constexpr MsgType kType = MsgType::kConfig;
  static constexpr std::size_t kPayloadSize = 41;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  StrategyCode strategy = StrategyCode::kGeojcbb;
  float confidence = 0.99f;          ///< chi-square level of the compatibility tests, (0, 1)
  float new_landmark_level = 0.999f; ///< level beyond which an observation is a new landmark, (0, 1)
  float local_radius_m = 10.0f;      ///< local region radius r + d, > 0
  std::uint8_t groups = 3;           ///< K for k-means / GMM-EM (0: chosen by BIC)
  bool condition_groups = false;
  float dbscan_eps_m = 1.5f;         ///< > 0
  std::uint8_t dbscan_min_points = 2;  ///< >= 1
  std::uint32_t node_budget = 4000;  ///< JCBB nodes per scan, >= 1
  float min_range_m = 0.0f;          ///< >= 0
  float max_range_m = 10.0f;         ///< > min_range_m
  float half_fov_rad = kPiF;         ///< (0, pi]
  std::uint8_t confirm_hits = 2;     ///< hits that confirm a tentative landmark, >= 1
  std::uint8_t max_misses = 3;       ///< misses in view that remove a tentative landmark, >= 1
  std::uint8_t max_tentative_reviews = 5;  ///< reviews a landmark may stay tentative, >= 1
  /// The device sends STATS unasked after the POSE of every this-many scans since CONFIG or RESET
  /// (0: only on request).
  std::uint16_t stats_period_scans = 0;

  [[nodiscard]] Error validate() const {
    const float f[] = {confidence, new_landmark_level, local_radius_m, dbscan_eps_m,
                       min_range_m, max_range_m, half_fov_rad};
    if (!detail::all_finite(f, sizeof f / sizeof f[0])) return Error::kNonFinite;
    const bool ok = static_cast<std::uint8_t>(strategy) < kStrategyCodeCount &&  //
                    confidence > 0.0f && confidence < 1.0f &&                    //
                    new_landmark_level > 0.0f && new_landmark_level < 1.0f &&   //
                    local_radius_m > 0.0f && dbscan_eps_m > 0.0f && dbscan_min_points >= 1 &&
                    node_budget >= 1 && min_range_m >= 0.0f && max_range_m > min_range_m &&
                    half_fov_rad > 0.0f && half_fov_rad <= kPiF && confirm_hits >= 1 &&
                    max_misses >= 1 && max_tentative_reviews >= 1;
    return ok ? Error::kOk : Error::kOutOfRange;
  }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.u8(static_cast<std::uint8_t>(strategy));
    w.f32(confidence);
    w.f32(new_landmark_level);
    w.f32(local_radius_m);
    w.u8(groups);
    w.u8(condition_groups ? 1 : 0);
    w.f32(dbscan_eps_m);
    w.u8(dbscan_min_points);
    w.u32(node_budget);
    w.f32(min_range_m);
    w.f32(max_range_m);
    w.f32(half_fov_rad);
    w.u8(confirm_hits);
    w.u8(max_misses);
    w.u8(max_tentative_reviews);
    w.u16(stats_period_scans);
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    const std::uint8_t s = r.u8();
    if (s >= kStrategyCodeCount) return Error::kOutOfRange;
    strategy = static_cast<StrategyCode>(s);
    confidence = r.f32();
    new_landmark_level = r.f32();
    local_radius_m = r.f32();
    groups = r.u8();
    const std::uint8_t cg = r.u8();
    if (cg > 1) return Error::kOutOfRange;
    condition_groups = cg == 1;
    dbscan_eps_m = r.f32();
    dbscan_min_points = r.u8();
    node_budget = r.u32();
    min_range_m = r.f32();
    max_range_m = r.f32();
    half_fov_rad = r.f32();
    confirm_hits = r.u8();
    max_misses = r.u8();
    max_tentative_reviews = r.u8();
    stats_period_scans = r.u16();
    return Error::kOk;
  }
};

/// ACK: a control message (CONFIG, RESET, ...) was accepted.
struct Ack : Codec<Ack> {
  static constexpr MsgType kType = MsgType::kAck;
  static constexpr std::size_t kPayloadSize = 3;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint8_t acked_type = 0;  ///< the MsgType of the accepted frame (not checked: a stray ACK matches nothing)
  std::uint16_t acked_seq = 0;

  [[nodiscard]] Error validate() const { return Error::kOk; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.u8(acked_type);
    w.u16(acked_seq);
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    acked_type = r.u8();
    acked_seq = r.u16();
    return Error::kOk;
  }
};

/// NACK: a frame was refused; error says why (any type number, known or not).
struct Nack : Codec<Nack> {
  static constexpr MsgType kType = MsgType::kNack;
  static constexpr std::size_t kPayloadSize = 4;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint8_t nacked_type = 0;
  std::uint16_t nacked_seq = 0;
  Error error = Error::kOutOfRange;  ///< kBadLength .. kInternal

  [[nodiscard]] Error validate() const { return detail::is_reportable(error) ? Error::kOk : Error::kOutOfRange; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.u8(nacked_type);
    w.u16(nacked_seq);
    w.u8(static_cast<std::uint8_t>(error));
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    nacked_type = r.u8();
    nacked_seq = r.u16();
    error = static_cast<Error>(r.u8());  // a fixed underlying type holds any u8; validate() checks it
    return Error::kOk;
  }
};

/// PING and PONG: link check; the device echoes the nonce.
template <MsgType Type>
struct NonceMsg : Codec<NonceMsg<Type>> {
  static constexpr MsgType kType = Type;
  static constexpr std::size_t kPayloadSize = 4;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint32_t nonce = 0;

  [[nodiscard]] Error validate() const { return Error::kOk; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const { w.u32(nonce); }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    nonce = r.u32();
    return Error::kOk;
  }
};
using Ping = NonceMsg<MsgType::kPing>;
using Pong = NonceMsg<MsgType::kPong>;

/// RESET, host -> device (acknowledged): restart the filter at this pose with an empty map.
struct Reset : Codec<Reset> {
  static constexpr MsgType kType = MsgType::kReset;
  static constexpr std::size_t kPayloadSize = 36;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  float x_m = 0.0f;        ///< world frame
  float y_m = 0.0f;
  float theta_rad = 0.0f;
  /// Pose covariance, upper triangle (p00, p01, p02, p11, p12, p22) over (x, y, theta); positive
  /// definite (symmetric by construction).
  std::array<float, 6> cov_upper{1e-6f, 0.0f, 0.0f, 1e-6f, 0.0f, 1e-6f};

  [[nodiscard]] Error validate() const {
    const float f[] = {x_m, y_m, theta_rad};
    if (!detail::all_finite(f, 3) || !detail::all_finite(cov_upper.data(), 6)) return Error::kNonFinite;
    return detail::spd3(cov_upper) ? Error::kOk : Error::kNotPositiveDefinite;
  }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.f32(x_m);
    w.f32(y_m);
    w.f32(theta_rad);
    detail::write_cov(w, cov_upper);
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    x_m = r.f32();
    y_m = r.f32();
    theta_rad = r.f32();
    detail::read_cov(r, cov_upper);
    return Error::kOk;
  }
};

/// SHUTDOWN, host -> device (acknowledged, only after HELLO): the device answers ACK, then calls the
/// board's shutdown hook with exit_code (the desktop device exits with it; the Cortex-M4F port ends
/// QEMU through semihosting). A board without a hook only acknowledges.
struct Shutdown : Codec<Shutdown> {
  static constexpr MsgType kType = MsgType::kShutdown;
  static constexpr std::size_t kPayloadSize = 1;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint8_t exit_code = 0;  ///< any

  [[nodiscard]] Error validate() const { return Error::kOk; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const { w.u8(exit_code); }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    exit_code = r.u8();
    return Error::kOk;
  }
};

/// ODOMETRY, host -> device (stream): velocity command over dt and its noise.
struct Odometry : Codec<Odometry> {
  static constexpr MsgType kType = MsgType::kOdometry;
  static constexpr std::size_t kPayloadSize = 20;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  float v_mps = 0.0f;          ///< forward speed, robot frame
  float w_radps = 0.0f;        ///< turn rate
  float dt_s = 0.0f;           ///< >= 0
  float sigma_v_mps = 0.0f;    ///< >= 0
  float sigma_w_radps = 0.0f;  ///< >= 0

  [[nodiscard]] Error validate() const {
    const float f[] = {v_mps, w_radps, dt_s, sigma_v_mps, sigma_w_radps};
    if (!detail::all_finite(f, 5)) return Error::kNonFinite;
    return (dt_s >= 0.0f && sigma_v_mps >= 0.0f && sigma_w_radps >= 0.0f) ? Error::kOk : Error::kOutOfRange;
  }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.f32(v_mps);
    w.f32(w_radps);
    w.f32(dt_s);
    w.f32(sigma_v_mps);
    w.f32(sigma_w_radps);
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    v_mps = r.f32();
    w_radps = r.f32();
    dt_s = r.f32();
    sigma_v_mps = r.f32();
    sigma_w_radps = r.f32();
    return Error::kOk;
  }
};

/// One range-bearing observation with its measurement covariance R (symmetric positive definite).
struct ObservationWire {
  float range_m = 0.0f;      ///< >= 0, robot frame
  float bearing_rad = 0.0f;  ///< [-pi, pi], robot frame
  float r00 = 1e-4f;         ///< R = [r00 r01; r01 r11], range then bearing
  float r01 = 0.0f;
  float r11 = 1e-4f;
};

/// OBS_BATCH, host -> device (stream): the observations of one scan.
/// @tparam MaxObs  capacity of the receiver (count on the wire is refused above it)
template <std::size_t MaxObs = kDefaultMaxObsPerBatch>
struct ObsBatchT : Codec<ObsBatchT<MaxObs>> {
  static constexpr MsgType kType = MsgType::kObsBatch;
  static constexpr std::size_t kFixedSize = 5;
  static constexpr std::size_t kItemSize = 20;
  static constexpr std::size_t kCapacity = MaxObs;
  static constexpr std::size_t kMaxPayloadSize = kFixedSize + MaxObs * kItemSize;
  static_assert(MaxObs >= 1 && MaxObs <= 255, "count is a u8");
  static_assert(kMaxPayloadSize <= kMaxPayload, "a full batch must fit one frame (MaxObs <= 50)");

  std::uint32_t batch_id = 0;
  std::uint8_t count = 0;  ///< <= MaxObs
  std::array<ObservationWire, MaxObs> obs{};

  [[nodiscard]] Error validate() const {
    if (count > MaxObs) return Error::kCapacityExceeded;
    for (std::size_t i = 0; i < count; ++i) {  // <= MaxObs
      const ObservationWire& o = obs[i];
      const float f[] = {o.range_m, o.bearing_rad, o.r00, o.r01, o.r11};
      if (!detail::all_finite(f, 5)) return Error::kNonFinite;
      if (!(o.range_m >= 0.0f) || !(o.bearing_rad >= -kPiF && o.bearing_rad <= kPiF)) return Error::kOutOfRange;
      if (!detail::spd2(o.r00, o.r01, o.r11)) return Error::kNotPositiveDefinite;
    }
    return Error::kOk;
  }
  [[nodiscard]] std::size_t payload_size() const { return kFixedSize + count * kItemSize; }
  void write(Writer& w) const {
    w.u32(batch_id);
    w.u8(count);
    for (std::size_t i = 0; i < count && i < MaxObs; ++i) {  // <= MaxObs
      w.f32(obs[i].range_m);
      w.f32(obs[i].bearing_rad);
      w.f32(obs[i].r00);
      w.f32(obs[i].r01);
      w.f32(obs[i].r11);
    }
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n < kFixedSize) return Error::kBadLength;
    Reader r(p, n);
    batch_id = r.u32();
    count = r.u8();
    if (count > MaxObs) return Error::kCapacityExceeded;
    if (n != kFixedSize + count * kItemSize) return Error::kBadLength;
    for (std::size_t i = 0; i < count; ++i) {  // <= MaxObs
      obs[i].range_m = r.f32();
      obs[i].bearing_rad = r.f32();
      obs[i].r00 = r.f32();
      obs[i].r01 = r.f32();
      obs[i].r11 = r.f32();
    }
    return Error::kOk;
  }
};
using ObsBatch = ObsBatchT<>;

/// Feature ids of ASSOC_RESULT besides map ids (>= 0).
constexpr std::int32_t kFeatureNew = -1;        ///< the observation starts a new landmark
constexpr std::int32_t kFeatureUnmatched = -2;  ///< clutter, or ambiguous: not used

/// What became of an observation (firmware_lib node::Outcome, value for value).
enum class PairingOutcome : std::uint8_t {
  kPaired = 0,    ///< feature_id: the map landmark it was paired with
  kNewLandmark,   ///< no compatible candidate; feature_id: the landmark it became
  kNewDropped,    ///< no compatible candidate, inside the augmentation gate: dropped (kFeatureNew)
  kUnmatched,     ///< ambiguous, left unpaired (kFeatureUnmatched)
  kNotAugmented,  ///< would have become a landmark, map full (kFeatureNew)
};
constexpr std::uint8_t kMaxPairingOutcome = 4;

struct PairingWire {
  PairingOutcome outcome = PairingOutcome::kUnmatched;
  std::int32_t feature_id = kFeatureUnmatched;  ///< >= 0, kFeatureNew or kFeatureUnmatched
  float d2 = 0.0f;  ///< Mahalanobis distance squared of the pairing: finite >= 0, or +inf (no candidate)
};

/// ASSOC_RESULT, device -> host: per observation of the batch, in order, its feature.
template <std::size_t MaxObs = kDefaultMaxObsPerBatch>
struct AssocResultT : Codec<AssocResultT<MaxObs>> {
  static constexpr MsgType kType = MsgType::kAssocResult;
  static constexpr std::size_t kFixedSize = 5;
  static constexpr std::size_t kItemSize = 9;
  static constexpr std::size_t kCapacity = MaxObs;
  static constexpr std::size_t kMaxPayloadSize = kFixedSize + MaxObs * kItemSize;
  static_assert(MaxObs >= 1 && MaxObs <= 255, "count is a u8");
  static_assert(kMaxPayloadSize <= kMaxPayload, "a full result must fit one frame (MaxObs <= 113)");

  std::uint32_t batch_id = 0;
  std::uint8_t count = 0;  ///< <= MaxObs
  std::array<PairingWire, MaxObs> pairs{};

  [[nodiscard]] Error validate() const {
    if (count > MaxObs) return Error::kCapacityExceeded;
    for (std::size_t i = 0; i < count; ++i) {  // <= MaxObs
      const PairingWire& q = pairs[i];
      if (static_cast<std::uint8_t>(q.outcome) > kMaxPairingOutcome) return Error::kOutOfRange;
      if (q.feature_id < kFeatureUnmatched) return Error::kOutOfRange;
      const bool has_id = q.outcome == PairingOutcome::kPaired || q.outcome == PairingOutcome::kNewLandmark;
      if (has_id != (q.feature_id >= 0)) return Error::kOutOfRange;
      if (is_nan(q.d2) || (!is_finite(q.d2) && !is_pos_inf(q.d2))) return Error::kNonFinite;
      if (!(q.d2 >= 0.0f)) return Error::kOutOfRange;
    }
    return Error::kOk;
  }
  [[nodiscard]] std::size_t payload_size() const { return kFixedSize + count * kItemSize; }
  void write(Writer& w) const {
    w.u32(batch_id);
    w.u8(count);
    for (std::size_t i = 0; i < count && i < MaxObs; ++i) {  // <= MaxObs
      w.u8(static_cast<std::uint8_t>(pairs[i].outcome));
      w.i32(pairs[i].feature_id);
      w.f32(pairs[i].d2);
    }
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n < kFixedSize) return Error::kBadLength;
    Reader r(p, n);
    batch_id = r.u32();
    count = r.u8();
    if (count > MaxObs) return Error::kCapacityExceeded;
    if (n != kFixedSize + count * kItemSize) return Error::kBadLength;
    for (std::size_t i = 0; i < count; ++i) {  // <= MaxObs
      pairs[i].outcome = static_cast<PairingOutcome>(r.u8());
      pairs[i].feature_id = r.i32();
      pairs[i].d2 = r.f32();
    }
    return Error::kOk;
  }
};
using AssocResult = AssocResultT<>;

/// POSE, device -> host: the filter's pose after a batch. The covariance is what the filter holds:
/// finite with a non-negative diagonal (the host judges consistency, for example NEES, itself).
struct Pose : Codec<Pose> {
  static constexpr MsgType kType = MsgType::kPose;
  static constexpr std::size_t kPayloadSize = 42;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint32_t batch_id = 0;
  float x_m = 0.0f;  ///< world frame
  float y_m = 0.0f;
  float theta_rad = 0.0f;
  std::array<float, 6> cov_upper{};  ///< (p00, p01, p02, p11, p12, p22) over (x, y, theta)
  std::uint16_t landmark_count = 0;

  [[nodiscard]] Error validate() const {
    const float f[] = {x_m, y_m, theta_rad};
    if (!detail::all_finite(f, 3) || !detail::all_finite(cov_upper.data(), 6)) return Error::kNonFinite;
    return (cov_upper[0] >= 0.0f && cov_upper[3] >= 0.0f && cov_upper[5] >= 0.0f) ? Error::kOk
                                                                                   : Error::kOutOfRange;
  }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.u32(batch_id);
    w.f32(x_m);
    w.f32(y_m);
    w.f32(theta_rad);
    detail::write_cov(w, cov_upper);
    w.u16(landmark_count);
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    batch_id = r.u32();
    x_m = r.f32();
    y_m = r.f32();
    theta_rad = r.f32();
    detail::read_cov(r, cov_upper);
    landmark_count = r.u16();
    return Error::kOk;
  }
};

/// STATS_REQUEST, host -> device: empty payload; the device answers STATS.
struct StatsRequest : Codec<StatsRequest> {
  static constexpr MsgType kType = MsgType::kStatsRequest;
  static constexpr std::size_t kPayloadSize = 0;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  [[nodiscard]] Error validate() const { return Error::kOk; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer&) const {}
  [[nodiscard]] Error read(const std::uint8_t*, std::size_t n) {
    return n == kPayloadSize ? Error::kOk : Error::kBadLength;
  }
};

/// STATS, device -> host: link counters (Decoder and message layer), pipeline counters, and the
/// instruction counts (DWT CYCCNT or QEMU icount) of the last scan by stage.
struct Stats : Codec<Stats> {
  static constexpr MsgType kType = MsgType::kStats;
  static constexpr std::size_t kFieldCount = 17;
  static constexpr std::size_t kPayloadSize = 4 * kFieldCount;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  std::uint32_t frames_ok = 0;
  std::uint32_t bad_crc = 0;
  std::uint32_t bad_length = 0;
  std::uint32_t overrun = 0;
  std::uint32_t unknown_type = 0;
  std::uint32_t bad_version = 0;
  std::uint32_t bad_flags = 0;
  std::uint32_t invalid_field = 0;  ///< frames whose payload failed validation
  std::uint32_t budget_hits = 0;    ///< scans that ran out of the JCBB node budget
  std::uint32_t scans = 0;          ///< scans processed
  std::uint32_t instr_predict = 0;
  std::uint32_t instr_predict_local = 0;
  std::uint32_t instr_associate = 0;
  std::uint32_t instr_update = 0;
  std::uint32_t instr_augment_review = 0;
  std::uint32_t instr_step = 0;     ///< the whole step
  std::uint32_t stack_high_water_bytes = 0;

  [[nodiscard]] Error validate() const { return Error::kOk; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    const std::uint32_t v[kFieldCount] = {frames_ok, bad_crc, bad_length, overrun, unknown_type, bad_version,
                                          bad_flags, invalid_field, budget_hits, scans, instr_predict,
                                          instr_predict_local, instr_associate, instr_update,
                                          instr_augment_review, instr_step, stack_high_water_bytes};
    for (const std::uint32_t x : v) w.u32(x);  // kFieldCount
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    std::uint32_t* const v[kFieldCount] = {&frames_ok, &bad_crc, &bad_length, &overrun, &unknown_type,
                                           &bad_version, &bad_flags, &invalid_field, &budget_hits, &scans,
                                           &instr_predict, &instr_predict_local, &instr_associate,
                                           &instr_update, &instr_augment_review, &instr_step,
                                           &stack_high_water_bytes};
    for (std::uint32_t* x : v) *x = r.u32();  // kFieldCount
    return Error::kOk;
  }
};

/// ERROR, device -> host: a frame was refused where no NACK applies (a stream message, or a frame
/// the device could not attribute), or the pipeline failed.
struct ErrorReport : Codec<ErrorReport> {
  static constexpr MsgType kType = MsgType::kError;
  static constexpr std::size_t kPayloadSize = 4;
  static constexpr std::size_t kMaxPayloadSize = kPayloadSize;

  Error error = Error::kInternal;  ///< kBadLength .. kInternal
  std::uint8_t offending_type = 0;
  std::uint16_t offending_seq = 0;

  [[nodiscard]] Error validate() const { return detail::is_reportable(error) ? Error::kOk : Error::kOutOfRange; }
  [[nodiscard]] std::size_t payload_size() const { return kPayloadSize; }
  void write(Writer& w) const {
    w.u8(static_cast<std::uint8_t>(error));
    w.u8(offending_type);
    w.u16(offending_seq);
  }
  [[nodiscard]] Error read(const std::uint8_t* p, std::size_t n) {
    if (n != kPayloadSize) return Error::kBadLength;
    Reader r(p, n);
    error = static_cast<Error>(r.u8());
    offending_type = r.u8();
    offending_seq = r.u16();
    return Error::kOk;
  }
};

// The schema text states every layout: a layout change that forgets the text does not compile.
namespace detail {
template <class M>
constexpr bool matches_schema_fixed() {
  constexpr SchemaLayout s = schema_layout(static_cast<std::uint8_t>(M::kType));
  return s.found && s.item_bytes == 0 && s.fixed_bytes == M::kPayloadSize;
}
template <class M>
constexpr bool matches_schema_list() {
  constexpr SchemaLayout s = schema_layout(static_cast<std::uint8_t>(M::kType));
  return s.found && s.fixed_bytes == M::kFixedSize && s.item_bytes == M::kItemSize;
}
constexpr bool all_types_in_schema() {
  for (const MsgType t : kAllMsgTypes) {  // <= 16
    if (!schema_layout(static_cast<std::uint8_t>(t)).found) return false;
  }
  return true;
}
}  // namespace detail
static_assert(detail::matches_schema_fixed<Hello>());
static_assert(detail::matches_schema_fixed<Capabilities>());
static_assert(detail::matches_schema_fixed<Config>());
static_assert(detail::matches_schema_fixed<Ack>());
static_assert(detail::matches_schema_fixed<Nack>());
static_assert(detail::matches_schema_fixed<Ping>());
static_assert(detail::matches_schema_fixed<Pong>());
static_assert(detail::matches_schema_fixed<Reset>());
static_assert(detail::matches_schema_fixed<Shutdown>());
static_assert(detail::matches_schema_fixed<Odometry>());
static_assert(detail::matches_schema_list<ObsBatch>());
static_assert(detail::matches_schema_list<AssocResult>());
static_assert(detail::matches_schema_fixed<Pose>());
static_assert(detail::matches_schema_fixed<StatsRequest>());
static_assert(detail::matches_schema_fixed<Stats>());
static_assert(detail::matches_schema_fixed<ErrorReport>());
static_assert(detail::all_types_in_schema());
static_assert(!schema_layout(0x00).found && !schema_layout(0xFF).found);

}  // namespace geojcbb::proto
