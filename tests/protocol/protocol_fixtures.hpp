// tests/protocol: shared fixtures of the protocol tests. Sample messages (valid, every byte pattern
// different from the defaults), payload and frame helpers, a hand-made frame (any header, any CRC), a
// byte-at-a-time feeder that collects frames and errors, and the schema text as a test oracle (field
// names, types and offsets parsed at run time). Tests may allocate; the library under test does not.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "geojcbb/protocol/protocol.hpp"

namespace proto_test {

using namespace geojcbb::proto;
using Bytes = std::vector<std::uint8_t>;

// ---------------------------------------------------------------------------------------------
// Sample messages: valid, with varied field values (every byte pattern differs from the defaults).

template <class M>
M sample();

template <>
inline Hello sample<Hello>() {
  return Hello{};
}
template <>
inline Capabilities sample<Capabilities>() {
  Capabilities c{};
  c.max_observations = 24;
  c.max_candidates = 32;
  c.max_groups = 5;
  c.max_landmarks = 64;
  c.max_jcbb_nodes = 4000;
  c.scalar_bytes = 4;
  c.boot_id = 0xA5A50001u;
  c.set_firmware_id("geojcbb-0.1.0");
  return c;
}
/// Field f of m set to a value other than its default and within its range: a bool negated; an
/// integer or enum the default + 1 (else - 1); a float the first of default x 0.5, + 0.125, - 0.125.
/// (CONFIG: every field, from its field list, so a field added to CONFIG is in the sample at once.)
template <class R, class T>
void set_other_than_default(R& m, const Field<R, T>& f) {
  T& v = m.*(f.member);
  const T d = v;
  if constexpr (std::is_same<T, bool>::value) {
    v = !d;
  } else if constexpr (std::is_floating_point<T>::value) {
    for (const float c : {d * 0.5f, d + 0.125f, d - 0.125f}) {
      if (c != d && check_float(f.range, c) == Error::kOk) {
        v = c;
        return;
      }
    }
  } else {
    using I = std::conditional_t<std::is_enum<T>::value, std::int64_t, T>;
    const auto k = static_cast<std::int64_t>(d);
    const auto top = static_cast<std::int64_t>(std::numeric_limits<I>::max());
    for (const std::int64_t c : {k + 1, k - 1}) {
      if (c >= 0 && c <= top && int_in_range(f.range, c)) {
        v = static_cast<T>(c);
        return;
      }
    }
  }
}
template <>
inline Config sample<Config>() {
  Config c{};
  std::apply([&c](const auto&... f) { (set_other_than_default(c, f), ...); }, Config::fields());
  return c;
}
template <>
inline Ack sample<Ack>() {
  Ack a{};
  a.acked_type = static_cast<std::uint8_t>(MsgType::kConfig);
  a.acked_seq = 0xBEEF;
  return a;
}
template <>
inline Nack sample<Nack>() {
  Nack n{};
  n.nacked_type = 0x55;
  n.nacked_seq = 513;
  n.error = Error::kUnknownType;
  return n;
}
template <>
inline Ping sample<Ping>() {
  Ping p{};
  p.nonce = 0x11223344u;
  return p;
}
template <>
inline Pong sample<Pong>() {
  Pong p{};
  p.nonce = 0xCAFEF00Du;
  return p;
}
template <>
inline Reset sample<Reset>() {
  Reset r{};
  r.x_m = 1.5f;
  r.y_m = -2.25f;
  r.theta_rad = 0.3f;
  r.cov_upper = {0.04f, 0.001f, -0.002f, 0.05f, 0.003f, 0.01f};
  return r;
}
template <>
inline Shutdown sample<Shutdown>() {
  Shutdown s{};
  s.exit_code = 0xA7;
  return s;
}
template <>
inline Relocalise sample<Relocalise>() {
  Relocalise r{};
  r.cov_upper = {225.0f, 0.5f, -0.25f, 196.0f, 0.125f, 9.5f};
  return r;
}
template <>
inline OdomDelta sample<OdomDelta>() {
  OdomDelta d{};
  d.dx_m = 0.25f;
  d.dy_m = -0.0625f;
  d.dtheta_rad = 0.03125f;
  d.cov_upper = {1e-4f, 1e-6f, -2e-6f, 4e-5f, 3e-7f, 2e-6f};
  return d;
}
template <>
inline Odometry sample<Odometry>() {
  Odometry o{};
  o.v_mps = 0.8f;
  o.w_radps = -0.12f;
  o.dt_s = 0.1f;
  o.sigma_v_mps = 0.05f;
  o.sigma_w_radps = 0.02f;
  return o;
}
inline ObsBatch obs_batch(int count, std::uint32_t id = 77) {
  ObsBatch b{};
  b.batch_id = id;
  b.count = static_cast<std::uint8_t>(count);
  for (int i = 0; i < count; ++i) {
    ObservationWire& o = b.obs[static_cast<std::size_t>(i)];
    o.range_m = 1.0f + 0.37f * static_cast<float>(i);
    o.bearing_rad = -3.0f + 0.25f * static_cast<float>(i);
    o.r00 = 0.01f + 0.001f * static_cast<float>(i);
    o.r01 = 0.0005f;
    o.r11 = 0.0009f;
  }
  return b;
}
template <>
inline ObsBatch sample<ObsBatch>() {
  return obs_batch(3);
}
template <>
inline AssocResult sample<AssocResult>() {
  AssocResult a{};
  a.batch_id = 77;
  a.count = 4;
  a.pairs[0] = {PairingOutcome::kPaired, 12, 1.5f};
  a.pairs[1] = {PairingOutcome::kNewDropped, kFeatureNew, 20.0f};
  a.pairs[2] = {PairingOutcome::kUnmatched, kFeatureUnmatched, std::numeric_limits<float>::infinity()};
  a.pairs[3] = {PairingOutcome::kNewLandmark, 0, 0.0f};
  return a;
}
template <>
inline Pose sample<Pose>() {
  Pose p{};
  p.batch_id = 77;
  p.x_m = 3.0f;
  p.y_m = 4.0f;
  p.theta_rad = -1.0f;
  p.cov_upper = {0.1f, 0.01f, 0.0f, 0.2f, -0.01f, 0.03f};
  p.landmark_count = 17;
  p.removed = 2;  // the scan removed two landmarks, named
  p.count = 2;
  p.ids[0].feature_id = 5;
  p.ids[1].feature_id = 9;
  return p;
}
template <>
inline SubmapAck sample<SubmapAck>() {
  SubmapAck a{};
  a.map_id = 7;
  a.send = true;
  return a;
}
template <>
inline Submap sample<Submap>() {  // chunk 1 of a 20-landmark map: landmarks 16..19
  Submap m{};
  m.map_id = 3;
  m.chunk = 1;
  m.chunks = static_cast<std::uint16_t>(submap_frames(20));
  m.landmarks = 20;
  m.first = 16;
  m.x_m = 12.5f;
  m.y_m = -3.25f;
  m.theta_rad = 0.75f;
  m.count = 4;
  for (std::uint8_t k = 0; k < m.count; ++k) m.items[k] = {40 + k, 1.0f + k, -2.0f * k, k % 2 == 0, k < 2, 4.5f * k};
  return m;
}
template <>
inline SubmapCov sample<SubmapCov>() {
  SubmapCov c{};
  c.map_id = 3;
  c.chunk = 2;
  c.chunks = 5;
  c.offset = 96;
  c.count = 3;
  c.items[0].v = 0.5f;
  c.items[1].v = -0.125f;
  c.items[2].v = 2.0f;
  return c;
}
inline SubmapSeed submap_seed(int count, std::uint32_t id = 78) {
  SubmapSeed s{};
  s.batch_id = id;
  s.map_id = 2;
  s.count = static_cast<std::uint8_t>(count);
  for (int k = 0; k < count; ++k) {
    SeedWire& w = s.items[static_cast<std::size_t>(k)];
    w.x_m = 4.0f + 1.5f * static_cast<float>(k);
    w.y_m = -1.0f + 0.5f * static_cast<float>(k);
    w.p00 = 0.25f + 0.01f * static_cast<float>(k);
    w.p01 = 0.02f;
    w.p11 = 0.5f;
    w.exist_nats = 20.0f + static_cast<float>(k);
  }
  return s;
}
template <>
inline SubmapSeed sample<SubmapSeed>() {
  return submap_seed(3);
}
template <>
inline StatsRequest sample<StatsRequest>() {
  return StatsRequest{};
}
template <>
inline Stats sample<Stats>() {
  Stats s{};
  s.frames_ok = 1000;
  s.bad_crc = 1;
  s.bad_length = 2;
  s.overrun = 3;
  s.unknown_type = 4;
  s.bad_version = 5;
  s.bad_flags = 6;
  s.invalid_field = 7;
  s.budget_hits = 8;
  s.scans = 999;
  s.instr_predict = 1200;
  s.instr_predict_local = 3400;
  s.instr_associate = 250000;
  s.instr_update = 90000;
  s.instr_augment_review = 15000;
  s.instr_existence = 6000;
  s.instr_relocalise = 250000;
  s.instr_loop = 120000;
  s.instr_window = 40000;
  s.instr_lost_test = 4000;
  s.instr_score = 30000;
  s.instr_step = 360000;
  s.stack_high_water_bytes = 2048;
  return s;
}
template <>
inline ErrorReport sample<ErrorReport>() {
  ErrorReport e{};
  e.error = Error::kNotReady;
  e.offending_type = static_cast<std::uint8_t>(MsgType::kObsBatch);
  e.offending_seq = 9;
  return e;
}

template <class M>
Bytes payload_of(const M& m) {
  std::array<std::uint8_t, M::kMaxPayloadSize> buf{};
  std::size_t n = 0;
  REQUIRE(m.encode(buf.data(), buf.size(), n) == Error::kOk);
  return Bytes(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
}

template <class M>
Bytes frame_of(const M& m, std::uint16_t seq = 1, std::uint8_t fl = 0) {
  EncodedFrame ef;
  REQUIRE(encode_message(m, seq, fl, ef) == Error::kOk);
  return Bytes(ef.bytes.begin(), ef.bytes.begin() + static_cast<std::ptrdiff_t>(ef.size));
}

/// A frame assembled by hand: any version, flags, len field and CRC (to reach checks after CRC).
inline Bytes raw_frame(std::uint8_t ver, std::uint8_t fl, std::uint8_t type, std::uint16_t seq, std::uint16_t len_field,
                       const Bytes& payload, bool good_crc = true) {
  Bytes f = {ver, fl, type, 0, 0, 0, 0, 0};
  put_u16_le(f.data() + 4, seq);
  put_u16_le(f.data() + 6, len_field);
  f.insert(f.end(), payload.begin(), payload.end());
  std::uint32_t crc = crc32c(f.data(), f.size());
  if (!good_crc) crc ^= 1u;
  f.resize(f.size() + 4);
  put_u32_le(f.data() + f.size() - 4, crc);
  Bytes out(cobs_max_encoded_size(f.size()) + 1);
  std::size_t n = 0;
  REQUIRE(cobs_encode(f.data(), f.size(), out.data(), out.size(), n) == Error::kOk);
  out.resize(n);
  out.push_back(0);
  return out;
}

struct Received {
  std::uint8_t type = 0;
  std::uint8_t flags = 0;
  std::uint16_t seq = 0;
  Bytes payload;
};

/// Feeds bytes one at a time; collects frames (copied out) and errors.
struct Feed {
  std::vector<Received> frames;
  std::vector<Error> errors;
};
inline Feed feed(Decoder& d, const Bytes& bytes) {
  Feed out;
  for (const std::uint8_t b : bytes) {
    FrameView f;
    const Error e = d.push(b, f);
    if (e == Error::kOk) {
      out.frames.push_back({f.type, f.flags, f.seq, Bytes(f.payload, f.payload + f.len)});
    } else if (e != Error::kIncomplete) {
      out.errors.push_back(e);
    }
  }
  return out;
}

inline std::uint32_t total_errors(const DecoderCounters& c) {
  return c.bad_crc + c.bad_length + c.overrun + c.bad_version + c.bad_flags;
}

inline FrameView view_of(const Received& r) {
  FrameView f;
  f.type = r.type;
  f.flags = r.flags;
  f.seq = r.seq;
  f.payload = r.payload.data();
  f.len = static_cast<std::uint16_t>(r.payload.size());
  return f;
}

// ---------------------------------------------------------------------------------------------
// The schema text as a test oracle: field types and offsets, parsed at run time.

struct SchemaField {
  std::string name;
  std::string type;
  std::size_t offset = 0;
};
/// Fields of `type` laid out for `count` list items (offsets in the payload).
inline std::vector<SchemaField> schema_fields(MsgType type, std::size_t count = 0) {
  const std::string text(kSchemaText, kSchemaTextLength);
  char tag[16];
  std::snprintf(tag, sizeof tag, "msg 0x%02X ", static_cast<unsigned>(type));
  const std::size_t at = text.find(tag);
  REQUIRE(at != std::string::npos);
  const std::string line = text.substr(at, text.find('\n', at) - at);
  std::vector<std::pair<std::string, std::string>> fixed, item;
  bool repeated = false;
  std::size_t pos = 0;
  while (pos < line.size()) {
    const std::size_t end = std::min(line.find(' ', pos), line.size());
    const std::string tok = line.substr(pos, end - pos);
    pos = end + 1;
    if (tok == "repeat") {
      repeated = true;
      continue;
    }
    const std::size_t colon = tok.find(':');
    if (colon == std::string::npos) continue;
    std::string ty = tok.substr(colon + 1);
    ty = ty.substr(0, ty.find('{'));
    (repeated ? item : fixed).emplace_back(tok.substr(0, colon), ty);
  }
  auto size_of = [](const std::string& t) -> std::size_t {
    return t == "u8" ? 1 : t == "u16" ? 2 : t == "c16" ? 16 : 4;
  };
  std::vector<SchemaField> out;
  std::size_t off = 0;
  for (const auto& [n, t] : fixed) {
    out.push_back({n, t, off});
    off += size_of(t);
  }
  for (std::size_t i = 0; i < count; ++i) {
    for (const auto& [n, t] : item) {
      out.push_back({n, t, off});
      off += size_of(t);
    }
  }
  return out;
}

}  // namespace proto_test
