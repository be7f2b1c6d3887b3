// tests/protocol: the serial link (protocol/). Round trip of every message, whole and one byte at a
// time; CRC check value; COBS; every truncation point and every single-bit flip of small frames;
// garbage, empty and oversize frames; capacities, NaN/Inf in every float field (offsets taken from
// the schema text), len against count, unknown types, flags, version, schema hash.
// Tests may allocate (std::vector); the library under test does not.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "geojcbb/protocol/protocol.hpp"

namespace {

using namespace geojcbb::proto;
using Bytes = std::vector<std::uint8_t>;

// ---------------------------------------------------------------------------------------------
// Sample messages: valid, with varied field values (every byte pattern differs from the defaults).

template <class M>
M sample();

template <>
Hello sample<Hello>() {
  return Hello{};
}
template <>
Capabilities sample<Capabilities>() {
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
template <>
Config sample<Config>() {
  Config c{};
  c.strategy = StrategyCode::kDfjcbb;
  c.confidence = 0.95f;
  c.new_landmark_level = 0.9999f;
  c.local_radius_m = 7.5f;
  c.groups = 4;
  c.condition_groups = true;
  c.dbscan_eps_m = 1.25f;
  c.dbscan_min_points = 3;
  c.node_budget = 123456;
  c.min_range_m = 0.3f;
  c.max_range_m = 12.0f;
  c.half_fov_rad = 1.5f;
  c.confirm_hits = 2;
  c.max_misses = 4;
  c.max_tentative_reviews = 6;
  c.stats_period_scans = 0x1234;
  return c;
}
template <>
Ack sample<Ack>() {
  Ack a{};
  a.acked_type = static_cast<std::uint8_t>(MsgType::kConfig);
  a.acked_seq = 0xBEEF;
  return a;
}
template <>
Nack sample<Nack>() {
  Nack n{};
  n.nacked_type = 0x55;
  n.nacked_seq = 513;
  n.error = Error::kUnknownType;
  return n;
}
template <>
Ping sample<Ping>() {
  Ping p{};
  p.nonce = 0x11223344u;
  return p;
}
template <>
Pong sample<Pong>() {
  Pong p{};
  p.nonce = 0xCAFEF00Du;
  return p;
}
template <>
Reset sample<Reset>() {
  Reset r{};
  r.x_m = 1.5f;
  r.y_m = -2.25f;
  r.theta_rad = 0.3f;
  r.cov_upper = {0.04f, 0.001f, -0.002f, 0.05f, 0.003f, 0.01f};
  return r;
}
template <>
Shutdown sample<Shutdown>() {
  Shutdown s{};
  s.exit_code = 0xA7;
  return s;
}
template <>
Odometry sample<Odometry>() {
  Odometry o{};
  o.v_mps = 0.8f;
  o.w_radps = -0.12f;
  o.dt_s = 0.1f;
  o.sigma_v_mps = 0.05f;
  o.sigma_w_radps = 0.02f;
  return o;
}
ObsBatch obs_batch(int count, std::uint32_t id = 77) {
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
ObsBatch sample<ObsBatch>() {
  return obs_batch(3);
}
template <>
AssocResult sample<AssocResult>() {
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
Pose sample<Pose>() {
  Pose p{};
  p.batch_id = 77;
  p.x_m = 3.0f;
  p.y_m = 4.0f;
  p.theta_rad = -1.0f;
  p.cov_upper = {0.1f, 0.01f, 0.0f, 0.2f, -0.01f, 0.03f};
  p.landmark_count = 17;
  return p;
}
template <>
StatsRequest sample<StatsRequest>() {
  return StatsRequest{};
}
template <>
Stats sample<Stats>() {
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
  s.instr_step = 360000;
  s.stack_high_water_bytes = 2048;
  return s;
}
template <>
ErrorReport sample<ErrorReport>() {
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
Bytes raw_frame(std::uint8_t ver, std::uint8_t fl, std::uint8_t type, std::uint16_t seq, std::uint16_t len_field,
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
Feed feed(Decoder& d, const Bytes& bytes) {
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

std::uint32_t total_errors(const DecoderCounters& c) {
  return c.bad_crc + c.bad_length + c.overrun + c.bad_version + c.bad_flags;
}

FrameView view_of(const Received& r) {
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

struct Field {
  std::string name;
  std::string type;
  std::size_t offset = 0;
};
/// Fields of `type` laid out for `count` list items (offsets in the payload).
std::vector<Field> schema_fields(MsgType type, std::size_t count = 0) {
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
  std::vector<Field> out;
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

}  // namespace

// ---------------------------------------------------------------------------------------------

TEST_CASE("protocol: CRC-32C check value and incremental update") {
  const char* s = "123456789";
  const auto* p = reinterpret_cast<const std::uint8_t*>(s);
  CHECK(crc32c(p, 9) == 0xE3069283u);
  CHECK(crc32c_final(crc32c_update(crc32c_update(kCrc32cInit, p, 4), p + 4, 5)) == 0xE3069283u);
  std::uint32_t st = kCrc32cInit;
  for (int i = 0; i < 9; ++i) st = crc32c_update(st, p[i]);
  CHECK(crc32c_final(st) == 0xE3069283u);
  CHECK(crc32c(nullptr, 0) == 0u);
}

TEST_CASE("protocol: COBS round trip, worst-case size and malformed input") {
  for (const std::size_t n : {0u, 1u, 2u, 253u, 254u, 255u, 508u, 509u, 1036u}) {
    for (const int pattern : {0, 1, 2}) {  // all zero, no zero, mixed
      Bytes in(n);
      for (std::size_t i = 0; i < n; ++i) {
        in[i] = pattern == 0 ? 0 : pattern == 1 ? static_cast<std::uint8_t>(1 + i % 255)
                                                : static_cast<std::uint8_t>(i % 7 == 0 ? 0 : i);
      }
      Bytes enc(cobs_max_encoded_size(n));
      std::size_t m = 0;
      REQUIRE(cobs_encode(in.data(), n, enc.data(), enc.size(), m) == Error::kOk);
      CHECK(m <= cobs_max_encoded_size(n));
      if (pattern == 1 && n > 0) CHECK(m == cobs_max_encoded_size(n));  // no zero: the worst case
      for (std::size_t i = 0; i < m; ++i) REQUIRE(enc[i] != 0);
      Bytes dec(n + 1);
      std::size_t k = 0;
      REQUIRE(cobs_decode(enc.data(), m, dec.data(), dec.size(), k) == Error::kOk);
      CHECK(k == n);
      CHECK(std::equal(in.begin(), in.end(), dec.begin()));
      // In place.
      REQUIRE(cobs_decode(enc.data(), m, enc.data(), enc.size(), k) == Error::kOk);
      CHECK(std::equal(in.begin(), in.end(), enc.begin()));
      // Output one byte short.
      Bytes enc2(m - 1 + 1);
      std::size_t w = 12345;
      CHECK(cobs_encode(in.data(), n, enc2.data(), m - 1, w) == Error::kBufferTooSmall);
      CHECK(w == 12345);
    }
  }
  std::size_t k = 0;
  std::uint8_t out[8];
  const std::uint8_t zero_inside[] = {3, 1, 0};
  CHECK(cobs_decode(zero_inside, 3, out, 8, k) == Error::kBadLength);
  const std::uint8_t past_end[] = {5, 1, 2};
  CHECK(cobs_decode(past_end, 3, out, 8, k) == Error::kBadLength);
  const std::uint8_t code_zero[] = {0};
  CHECK(cobs_decode(code_zero, 1, out, 8, k) == Error::kBadLength);
  CHECK(cobs_decode(code_zero, 0, out, 8, k) == Error::kBadLength);
}

TEST_CASE("protocol: little-endian header and fields, golden PING frame") {
  Ping p{};
  p.nonce = 0x11223344u;
  const Bytes wire = frame_of(p, 0x0102, flags::kAckRequested);
  REQUIRE(wire.back() == 0);
  Bytes f(wire.size());
  std::size_t n = 0;
  REQUIRE(cobs_decode(wire.data(), wire.size() - 1, f.data(), f.size(), n) == Error::kOk);
  REQUIRE(n == 16);
  const Bytes head(f.begin(), f.begin() + 12);
  CHECK(head == Bytes{0x01, 0x01, 0x06, 0x00, 0x02, 0x01, 0x04, 0x00, 0x44, 0x33, 0x22, 0x11});
  CHECK(get_u32_le(f.data() + 12) == crc32c(f.data(), 12));
  // float32 bit pattern, little-endian.
  Odometry o = sample<Odometry>();
  o.v_mps = 1.0f;  // 0x3F800000
  const Bytes pl = payload_of(o);
  CHECK(Bytes(pl.begin(), pl.begin() + 4) == Bytes{0x00, 0x00, 0x80, 0x3F});
  // i32 two's complement.
  AssocResult a = sample<AssocResult>();
  const Bytes ap = payload_of(a);
  CHECK(ap[14] == 2);                                                                  // pairs[1].outcome
  CHECK(Bytes(ap.begin() + 15, ap.begin() + 19) == Bytes{0xFF, 0xFF, 0xFF, 0xFF});  // pairs[1].feature_id = -1
}

TEST_CASE_TEMPLATE("protocol: round trip of every message, whole and one byte at a time", M, Hello, Capabilities,
                   Config, Ack, Nack, Ping, Pong, Reset, Shutdown, Odometry, ObsBatch, AssocResult, Pose, StatsRequest,
                   Stats, ErrorReport) {
  const M m = sample<M>();
  const Bytes payload = payload_of(m);
  CHECK(payload.size() == m.payload_size());
  CHECK(payload.size() <= M::kMaxPayloadSize);
  const Bytes wire = frame_of(m, 4242, flags::kAckRequested);
  CHECK(wire.size() <= max_wire_size(payload.size()));

  SUBCASE("whole") {
    Decoder d;
    FrameView f;
    std::size_t used = 0;
    REQUIRE(d.push(wire.data(), wire.size(), f, used) == Error::kOk);
    CHECK(used == wire.size());
    CHECK(f.type == static_cast<std::uint8_t>(M::kType));
    CHECK(f.seq == 4242);
    CHECK(f.flags == flags::kAckRequested);
    M out{};
    REQUIRE(decode_message(f, out) == Error::kOk);
    CHECK(payload_of(out) == payload);
    CHECK(d.counters().frames_ok == 1);
    CHECK(total_errors(d.counters()) == 0);
  }
  SUBCASE("one byte at a time, three frames in a row") {
    Decoder d;
    for (int rep = 0; rep < 3; ++rep) {
      for (std::size_t i = 0; i < wire.size(); ++i) {
        FrameView f;
        const Error e = d.push(wire[i], f);
        if (i + 1 < wire.size()) {
          REQUIRE(e == Error::kIncomplete);
        } else {
          REQUIRE(e == Error::kOk);
          int visits = 0;
          CHECK(dispatch(f, [&](const auto& msg) {
                  ++visits;
                  CHECK(std::is_same_v<std::decay_t<decltype(msg)>, M>);
                  CHECK(payload_of(msg) == payload);
                }) == Error::kOk);
          CHECK(visits == 1);
        }
      }
    }
    CHECK(d.counters().frames_ok == 3);
    CHECK(total_errors(d.counters()) == 0);
    CHECK(d.pending() == 0);
  }
  SUBCASE("payload truncated or extended by one byte") {
    M out = m;
    if (!payload.empty()) {
      CHECK(out.decode(payload.data(), payload.size() - 1) == Error::kBadLength);
    }
    Bytes longer = payload;
    longer.push_back(0);
    CHECK(out.decode(longer.data(), longer.size()) == Error::kBadLength);
    CHECK(payload_of(out) == payload);
  }
  SUBCASE("a value-initialised message is valid") {
    const M zero{};
    CHECK(zero.validate() == Error::kOk);
    CHECK(payload_of(zero).size() == zero.payload_size());
  }
  SUBCASE("schema text states this layout") {
    const SchemaLayout s = schema_layout(static_cast<std::uint8_t>(M::kType));
    CHECK(s.found);
    std::size_t expected = s.fixed_bytes;
    if constexpr (std::is_same_v<M, ObsBatch> || std::is_same_v<M, AssocResult>) expected += m.count * s.item_bytes;
    CHECK(payload.size() == expected);
  }
}

TEST_CASE("protocol: maximum payload frame and encoder buffer bounds") {
  Bytes payload(kMaxPayload);
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<std::uint8_t>(1 + i % 250);
  EncodedFrame ef;
  REQUIRE(encode_frame(0x55, 7, 0, payload.data(), payload.size(), ef) == Error::kOk);
  CHECK(ef.size <= kMaxEncodedFrame);
  Decoder d;
  FrameView f;
  std::size_t used = 0;
  REQUIRE(d.push(ef.bytes.data(), ef.size, f, used) == Error::kOk);
  CHECK(Bytes(f.payload, f.payload + f.len) == payload);

  Bytes too_big(kMaxPayload + 1, 1);
  CHECK(encode_frame(0x55, 7, 0, too_big.data(), too_big.size(), ef) == Error::kBadLength);
  CHECK(encode_frame(0x55, 7, 0, nullptr, 3, ef) == Error::kBadLength);

  const Bytes good = frame_of(sample<Odometry>());
  const Bytes pl = payload_of(sample<Odometry>());
  for (std::size_t cap = 0; cap < good.size(); ++cap) {
    Bytes out(cap + 1, 0xEE);
    std::size_t written = 999;
    CHECK(encode_frame(static_cast<std::uint8_t>(MsgType::kOdometry), 1, 0, pl.data(), pl.size(), out.data(), cap,
                       written) == Error::kBufferTooSmall);
    CHECK(written == 999);
    CHECK(out[cap] == 0xEE);  // nothing written past cap
  }
  std::size_t written = 0;
  Bytes out(good.size());
  CHECK(encode_frame(static_cast<std::uint8_t>(MsgType::kOdometry), 1, 0, pl.data(), pl.size(), out.data(), out.size(),
                     written) == Error::kOk);
  CHECK(out == good);
}

TEST_CASE("protocol: every truncation point of a frame is rejected and the decoder resynchronises") {
  for (const Bytes& wire : {frame_of(sample<Ping>()), frame_of(obs_batch(3)), frame_of(sample<Config>())}) {
    const Bytes body(wire.begin(), wire.end() - 1);
    for (std::size_t k = 1; k < body.size(); ++k) {
      CAPTURE(k);
      Decoder d;
      Bytes cut(body.begin(), body.begin() + static_cast<std::ptrdiff_t>(k));
      cut.push_back(0);
      const Feed a = feed(d, cut);
      CHECK(a.frames.empty());
      CHECK(a.errors.size() == 1);
      CHECK(d.counters().bad_crc + d.counters().bad_length == 1);
      CHECK(d.counters().frames_ok == 0);
      const Feed b = feed(d, wire);
      CHECK(b.frames.size() == 1);
      CHECK(d.counters().frames_ok == 1);
    }
    // A truncated frame followed directly by a good one without a delimiter in between: the two
    // merge into one bad frame; the next good frame is received.
    Decoder d;
    Bytes stream(body.begin(), body.begin() + 5);
    stream.insert(stream.end(), wire.begin(), wire.end());
    stream.insert(stream.end(), wire.begin(), wire.end());
    const Feed r = feed(d, stream);
    CHECK(r.frames.size() == 1);
    CHECK(total_errors(d.counters()) == 1);
  }
}

namespace {
/// What the decoder must count for one non-empty COBS body (reference model of Decoder::check).
enum class Cause { kNone, kBadLength, kBadCrc, kOther };
Cause expected_cause(const Bytes& piece) {
  if (piece.empty()) return Cause::kNone;
  Bytes f(piece.size());
  std::size_t m = 0;
  if (cobs_decode(piece.data(), piece.size(), f.data(), f.size(), m) != Error::kOk || m < 12) return Cause::kBadLength;
  if (crc32c(f.data(), m - 4) != get_u32_le(f.data() + m - 4)) return Cause::kBadCrc;
  return Cause::kOther;  // would need a CRC collision: must not happen for these frames
}
/// Indices of COBS code bytes in a body.
std::vector<bool> code_bytes(const Bytes& body) {
  std::vector<bool> is_code(body.size(), false);
  std::size_t i = 0;
  while (i < body.size()) {
    is_code[i] = true;
    i += body[i];
  }
  return is_code;
}
}  // namespace

TEST_CASE("protocol: every single-bit flip of small frames is rejected and counted exactly") {
  const std::vector<std::pair<const char*, Bytes>> frames = {
      {"PING", frame_of(sample<Ping>(), 3)},
      {"ODOMETRY", frame_of(sample<Odometry>(), 4)},
      {"OBS_BATCH x3", frame_of(obs_batch(3), 5)},
  };
  for (const auto& [name, wire] : frames) {
    CAPTURE(name);
    const Bytes body(wire.begin(), wire.end() - 1);
    const std::vector<bool> is_code = code_bytes(body);
    int splits = 0;
    for (std::size_t i = 0; i < body.size(); ++i) {
      for (int bit = 0; bit < 8; ++bit) {
        CAPTURE(i);
        CAPTURE(bit);
        Bytes flipped = wire;
        flipped[i] = static_cast<std::uint8_t>(flipped[i] ^ (1u << bit));
        std::uint32_t expect_len = 0;
        std::uint32_t expect_crc = 0;
        auto expect = [&](const Bytes& piece) {
          const Cause c = expected_cause(piece);
          REQUIRE(c != Cause::kOther);
          expect_len += c == Cause::kBadLength ? 1 : 0;
          expect_crc += c == Cause::kBadCrc ? 1 : 0;
        };
        if (flipped[i] == 0) {  // the flip made a delimiter: two pieces (an empty one is ignored)
          ++splits;
          expect(Bytes(flipped.begin(), flipped.begin() + static_cast<std::ptrdiff_t>(i)));
          expect(Bytes(flipped.begin() + static_cast<std::ptrdiff_t>(i) + 1, flipped.end() - 1));
          CHECK(expect_len + expect_crc == (i > 0 ? 1u : 0u) + (i + 1 < body.size() ? 1u : 0u));
        } else {
          expect(Bytes(flipped.begin(), flipped.end() - 1));
          CHECK(expect_len + expect_crc == 1);
          if (!is_code[i]) CHECK(expect_crc == 1);  // a data bit: the CRC catches it
        }
        Decoder d;
        const Feed r = feed(d, flipped);
        CHECK(r.frames.empty());
        CHECK(d.counters().frames_ok == 0);
        CHECK(d.counters().bad_length == expect_len);
        CHECK(d.counters().bad_crc == expect_crc);
        CHECK(d.counters().overrun == 0);
        CHECK(d.counters().bad_version == 0);
        CHECK(d.counters().bad_flags == 0);
        CHECK(r.errors.size() == expect_len + expect_crc);
        // Resynchronised: the next frame is received.
        const Feed next = feed(d, wire);
        CHECK(next.frames.size() == 1);
      }
    }
    CHECK(splits > 0);  // some flips produced a 0x00 (a byte with a single bit set)
  }
}

TEST_CASE("protocol: garbage between frames, empty frames, back-to-back delimiters") {
  const Bytes a = frame_of(sample<Ping>(), 1);
  const Bytes b = frame_of(obs_batch(5), 2);
  std::uint32_t lcg = 12345;
  auto garbage = [&](std::size_t n, bool end_with_delimiter) {
    Bytes g(n);
    for (auto& x : g) {
      lcg = lcg * 1664525u + 1013904223u;
      x = static_cast<std::uint8_t>(lcg >> 24);
    }
    if (end_with_delimiter) g.push_back(0);
    return g;
  };
  SUBCASE("garbage closed by a delimiter costs nothing but itself") {
    Bytes stream = {0, 0, 0};
    int sent = 0;
    for (int k = 0; k < 50; ++k) {
      const Bytes g = garbage(1 + static_cast<std::size_t>(k) * 7, true);
      stream.insert(stream.end(), g.begin(), g.end());
      const Bytes& f = (k % 2) ? a : b;
      stream.insert(stream.end(), f.begin(), f.end());
      stream.push_back(0);  // an empty frame: ignored
      ++sent;
    }
    Decoder d;
    const Feed r = feed(d, stream);
    CHECK(r.frames.size() == static_cast<std::size_t>(sent));
    CHECK(d.counters().frames_ok == static_cast<std::uint32_t>(sent));
    CHECK(total_errors(d.counters()) == r.errors.size());
    for (const Received& x : r.frames) CHECK((x.seq == 1 || x.seq == 2));
  }
  SUBCASE("garbage without a delimiter spoils exactly the next frame") {
    Bytes stream;
    Bytes g = garbage(9, false);
    for (auto& x : g) x = x == 0 ? 1 : x;
    stream.insert(stream.end(), g.begin(), g.end());
    stream.insert(stream.end(), a.begin(), a.end());
    stream.insert(stream.end(), b.begin(), b.end());
    Decoder d;
    const Feed r = feed(d, stream);
    REQUIRE(r.frames.size() == 1);
    CHECK(r.frames[0].seq == 2);
    CHECK(total_errors(d.counters()) == 1);
  }
  SUBCASE("only delimiters") {
    Decoder d;
    const Feed r = feed(d, Bytes(100, 0));
    CHECK(r.frames.empty());
    CHECK(r.errors.empty());
    CHECK(total_errors(d.counters()) == 0);
  }
}

TEST_CASE("protocol: oversize frames are an overrun, counted once, and the decoder recovers") {
  Decoder d;
  Bytes stream(2 * kMaxEncodedBody + 17, 0x5A);
  stream.push_back(0);
  const Feed r = feed(d, stream);
  CHECK(r.frames.empty());
  REQUIRE(r.errors.size() == 1);
  CHECK(r.errors[0] == Error::kOverrun);
  CHECK(d.counters().overrun == 1);
  CHECK(total_errors(d.counters()) == 1);
  CHECK(d.pending() == 0);
  const Feed ok = feed(d, frame_of(sample<Pose>()));
  CHECK(ok.frames.size() == 1);

  // Exactly a full buffer is not an overrun (it fails later checks); one more byte is.
  Decoder e;
  Bytes full(kMaxEncodedBody, 0x5A);
  full.push_back(0);
  (void)feed(e, full);
  CHECK(e.counters().overrun == 0);
  CHECK(e.counters().bad_length + e.counters().bad_crc == 1);
  Bytes over(kMaxEncodedBody + 1, 0x5A);
  over.push_back(0);
  (void)feed(e, over);
  CHECK(e.counters().overrun == 1);

  // A frame whose COBS body fits but whose decoded length exceeds kMaxPayload: bad_length.
  Bytes long_payload(kMaxPayload + 1, 0);  // zeros keep the COBS body within the buffer
  Decoder g;
  (void)feed(g, raw_frame(1, 0, 0x55, 1, static_cast<std::uint16_t>(long_payload.size()), long_payload));
  CHECK(g.counters().bad_length == 1);
  CHECK(g.counters().frames_ok == 0);
}

TEST_CASE("protocol: frame len field inconsistent with the frame, bad version, too short") {
  const Bytes pl = payload_of(sample<Ping>());
  const auto ping = static_cast<std::uint8_t>(MsgType::kPing);
  Decoder d;
  (void)feed(d, raw_frame(1, 0, ping, 1, 3, pl));
  (void)feed(d, raw_frame(1, 0, ping, 1, 5, pl));
  (void)feed(d, raw_frame(1, 0, ping, 1, 0xFFFF, pl));
  CHECK(d.counters().bad_length == 3);
  (void)feed(d, raw_frame(2, 0, ping, 1, 4, pl));
  (void)feed(d, raw_frame(0, 0, ping, 1, 4, pl));
  CHECK(d.counters().bad_version == 2);
  (void)feed(d, raw_frame(1, 0, ping, 1, 4, pl, false));
  CHECK(d.counters().bad_crc == 1);
  (void)feed(d, Bytes{0x05, 1, 2, 3, 4, 0});  // decodes to 4 bytes: shorter than header + CRC
  CHECK(d.counters().bad_length == 4);
  const Feed r = feed(d, raw_frame(1, 0, ping, 1, 4, pl));
  CHECK(r.frames.size() == 1);
  CHECK(d.counters().frames_ok == 1);
  CHECK(total_errors(d.counters()) == 7);
}

TEST_CASE("protocol: unknown compatible flags are ignored, unknown incompatible flags drop the frame") {
  const Bytes pl = payload_of(sample<Odometry>());
  const auto odo = static_cast<std::uint8_t>(MsgType::kOdometry);
  for (std::uint8_t bit = 0x01; bit != 0x10; bit = static_cast<std::uint8_t>(bit << 1)) {
    Decoder d;
    const Feed r = feed(d, raw_frame(1, bit, odo, 9, static_cast<std::uint16_t>(pl.size()), pl));
    REQUIRE(r.frames.size() == 1);
    CHECK(r.frames[0].flags == bit);
    Odometry o{};
    CHECK(decode_message(view_of(r.frames[0]), o) == Error::kOk);
  }
  std::uint32_t dropped = 0;
  Decoder d;
  for (std::uint8_t bit = 0x10; bit != 0; bit = static_cast<std::uint8_t>(bit << 1)) {
    const Feed r = feed(d, raw_frame(1, static_cast<std::uint8_t>(bit | 0x01), odo, 9,
                                     static_cast<std::uint16_t>(pl.size()), pl));
    CHECK(r.frames.empty());
    REQUIRE(r.errors.size() == 1);
    CHECK(r.errors[0] == Error::kBadFlags);
    ++dropped;
  }
  CHECK(d.counters().bad_flags == dropped);
  CHECK(dropped == 4);
}

TEST_CASE("protocol: unknown and unexpected message types") {
  MessageCounters mc;
  Decoder d;
  const Feed r = feed(d, raw_frame(1, 0, 0x55, 1, 0, {}));
  REQUIRE(r.frames.size() == 1);  // framing is fine: the message layer rejects it
  const FrameView f = view_of(r.frames[0]);
  bool visited = false;
  const Error e = dispatch(f, [&](const auto&) { visited = true; });
  CHECK(e == Error::kUnknownType);
  CHECK_FALSE(visited);
  mc.record(e);
  Ping p{};
  CHECK(decode_message(f, p) == Error::kUnknownType);
  CHECK(mc.unknown_type == 1);
  CHECK(mc.invalid_field == 0);

  const Feed pong = feed(d, frame_of(sample<Pong>()));
  REQUIRE(pong.frames.size() == 1);
  CHECK(decode_message(view_of(pong.frames[0]), p) == Error::kWrongType);
  CHECK(p.nonce == 0);
  Pong q{};
  CHECK(decode_message(view_of(pong.frames[0]), q) == Error::kOk);
  CHECK(q.nonce == sample<Pong>().nonce);

  for (int t = 0; t < 256; ++t) {
    const bool known = is_known_type(static_cast<std::uint8_t>(t));
    CHECK(known == schema_layout(static_cast<std::uint8_t>(t)).found);
  }
}

TEST_CASE("protocol: counts over capacity, exactly full, and len against count") {
  SUBCASE("OBS_BATCH") {
    ObsBatch full = obs_batch(24);
    CHECK(payload_of(full).size() == 5 + 24 * 20);
    ObsBatch over = full;
    over.count = 25;
    std::array<std::uint8_t, kMaxPayload> buf{};
    std::size_t n = 0;
    CHECK(over.encode(buf.data(), buf.size(), n) == Error::kCapacityExceeded);
    // On the wire: count 25 with a payload of exactly the right length.
    Bytes pl = payload_of(full);
    pl[4] = 25;
    pl.resize(5 + 25 * 20, 0);
    ObsBatch out = obs_batch(2, 1);
    const Bytes before = payload_of(out);
    CHECK(out.decode(pl.data(), pl.size()) == Error::kCapacityExceeded);
    pl[4] = 255;
    CHECK(out.decode(pl.data(), pl.size()) == Error::kCapacityExceeded);
    CHECK(payload_of(out) == before);
    // A smaller receiver refuses a batch over its own capacity.
    ObsBatchT<4> small{};
    const Bytes five = payload_of(obs_batch(5));
    CHECK(small.decode(five.data(), five.size()) == Error::kCapacityExceeded);
    const Bytes four = payload_of(obs_batch(4));
    CHECK(small.decode(four.data(), four.size()) == Error::kOk);
    // len against count.
    const Bytes three = payload_of(obs_batch(3));
    const std::size_t bad_lengths[] = {0, 4, 5, 5 + 2 * 20, 5 + 3 * 20 - 1};
    for (const std::size_t len : bad_lengths) {
      CHECK(out.decode(three.data(), len) == Error::kBadLength);
    }
    Bytes longer = three;
    longer.resize(5 + 4 * 20, 0x3F);
    CHECK(out.decode(longer.data(), longer.size()) == Error::kBadLength);
    CHECK(payload_of(out) == before);
    // Zero observations is a valid (empty) scan.
    const Bytes empty = payload_of(obs_batch(0));
    CHECK(empty.size() == 5);
    CHECK(out.decode(empty.data(), empty.size()) == Error::kOk);
    CHECK(out.count == 0);
  }
  SUBCASE("ASSOC_RESULT") {
    AssocResult full{};
    full.count = 24;
    const Bytes pl = payload_of(full);
    CHECK(pl.size() == 5 + 24 * 9);
    Bytes over = pl;
    over[4] = 25;
    over.resize(5 + 25 * 9, 0);
    AssocResult out = sample<AssocResult>();
    CHECK(out.decode(over.data(), over.size()) == Error::kCapacityExceeded);
    CHECK(out.decode(pl.data(), pl.size() - 8) == Error::kBadLength);
    CHECK(payload_of(out) == payload_of(sample<AssocResult>()));
    AssocResult enc = full;
    enc.count = 25;
    std::array<std::uint8_t, kMaxPayload> buf{};
    std::size_t n = 0;
    CHECK(enc.encode(buf.data(), buf.size(), n) == Error::kCapacityExceeded);
  }
}

namespace {
/// Writes a float bit pattern at every f32 field of a valid payload and checks the decode outcome;
/// the output struct must stay untouched whenever the decode fails.
template <class M>
void check_float_fields(const M& valid, std::size_t count = 0) {
  const Bytes pl = payload_of(valid);
  const std::vector<Field> fields = schema_fields(M::kType, count);
  int checked = 0;
  for (const Field& fd : fields) {
    if (fd.type != "f32") continue;
    for (const std::uint32_t bits : {0x7FC00000u, 0xFFC00000u, 0x7F800001u, 0x7F800000u, 0xFF800000u}) {
      CAPTURE(fd.name);
      CAPTURE(fd.offset);
      CAPTURE(bits);
      Bytes bad = pl;
      put_u32_le(bad.data() + fd.offset, bits);
      M out = M{};
      const Bytes before = payload_of(out);
      const Error e = out.decode(bad.data(), bad.size());
      const bool plus_inf_allowed = std::is_same_v<M, AssocResult> && fd.name == "d2" && bits == 0x7F800000u;
      if (plus_inf_allowed) {
        CHECK(e == Error::kOk);
      } else {
        CHECK(e == Error::kNonFinite);
        CHECK(payload_of(out) == before);
      }
      ++checked;
    }
  }
  CHECK(checked > 0);
}
}  // namespace

TEST_CASE("protocol: NaN and Inf in every float field are rejected") {
  check_float_fields(sample<Config>());
  check_float_fields(sample<Reset>());
  check_float_fields(sample<Odometry>());
  check_float_fields(obs_batch(3), 3);
  check_float_fields(sample<AssocResult>(), 4);
  check_float_fields(sample<Pose>());
  // Encoder side: a non-finite field is refused before anything is written.
  Odometry o = sample<Odometry>();
  o.dt_s = std::numeric_limits<float>::quiet_NaN();
  std::array<std::uint8_t, Odometry::kMaxPayloadSize> buf{};
  std::size_t n = 77;
  CHECK(o.encode(buf, n) == Error::kNonFinite);
  CHECK(n == 77);
  EncodedFrame ef;
  CHECK(encode_message(o, 1, 0, ef) == Error::kNonFinite);
  CHECK(ef.size == 0);
}

TEST_CASE("protocol: ranges and positive definiteness") {
  auto rejects = [](const auto& m, Error expected) {
    std::array<std::uint8_t, kMaxPayload> buf{};
    std::size_t n = 0;
    CHECK(m.encode(buf.data(), buf.size(), n) == expected);
  };
  SUBCASE("CONFIG") {
    const Config ok = sample<Config>();
    rejects(ok, Error::kOk);
    Config c = ok;
    c.confidence = 1.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.confidence = 0.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.new_landmark_level = 1.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.local_radius_m = 0.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.dbscan_eps_m = -1.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.dbscan_min_points = 0;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.node_budget = 0;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.min_range_m = -0.1f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.max_range_m = c.min_range_m;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.half_fov_rad = kPiF;
    rejects(c, Error::kOk);
    c.half_fov_rad = std::nextafter(kPiF, 4.0f);
    rejects(c, Error::kOutOfRange);
    c.half_fov_rad = 0.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.confirm_hits = 0;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.max_misses = 0;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.max_tentative_reviews = 0;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.groups = 0;  // 0: chosen by BIC
    rejects(c, Error::kOk);
    // Wire-only values: strategy 6 and condition_groups 2.
    Bytes pl = payload_of(ok);
    Config out = ok;
    pl[0] = 6;
    CHECK(out.decode(pl.data(), pl.size()) == Error::kOutOfRange);
    pl = payload_of(ok);
    pl[14] = 2;  // condition_groups (offset from the schema: 1 + 4 + 4 + 4 + 1)
    CHECK(schema_fields(MsgType::kConfig)[5].name == "condition_groups");
    CHECK(schema_fields(MsgType::kConfig)[5].offset == 14);
    CHECK(out.decode(pl.data(), pl.size()) == Error::kOutOfRange);
    for (std::uint8_t s = 0; s < kStrategyCodeCount; ++s) {
      pl = payload_of(ok);
      pl[0] = s;
      CHECK(out.decode(pl.data(), pl.size()) == Error::kOk);
      CHECK(static_cast<std::uint8_t>(out.strategy) == s);
    }
  }
  SUBCASE("RESET covariance") {
    Reset r = sample<Reset>();
    rejects(r, Error::kOk);
    r.cov_upper = {1.0f, 2.0f, 0.0f, 1.0f, 0.0f, 1.0f};  // indefinite 2x2 leading block
    rejects(r, Error::kNotPositiveDefinite);
    r.cov_upper = {1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f};  // singular
    rejects(r, Error::kNotPositiveDefinite);
    r.cov_upper = {-1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f};
    rejects(r, Error::kNotPositiveDefinite);
    r.cov_upper = {1.0f, 0.9f, 0.9f, 1.0f, 0.9f, 1.0f};  // positive definite (all minors > 0)
    rejects(r, Error::kOk);
    r.cov_upper = {1.0f, 0.9f, 0.9f, 1.0f, -0.9f, 1.0f};  // leading 2x2 fine, det < 0
    rejects(r, Error::kNotPositiveDefinite);
  }
  SUBCASE("ODOMETRY") {
    Odometry o = sample<Odometry>();
    o.dt_s = -0.001f;
    rejects(o, Error::kOutOfRange);
    o = sample<Odometry>();
    o.sigma_w_radps = -1.0f;
    rejects(o, Error::kOutOfRange);
    o = sample<Odometry>();
    o.v_mps = -5.0f;  // reversing is fine
    o.dt_s = 0.0f;
    rejects(o, Error::kOk);
  }
  SUBCASE("OBS_BATCH") {
    ObsBatch b = obs_batch(3);
    b.obs[2].range_m = -0.5f;
    rejects(b, Error::kOutOfRange);
    b = obs_batch(3);
    b.obs[1].bearing_rad = 3.2f;
    rejects(b, Error::kOutOfRange);
    b.obs[1].bearing_rad = -kPiF;
    rejects(b, Error::kOk);
    b.obs[0].r01 = 1.0f;  // r00 r11 < r01^2
    rejects(b, Error::kNotPositiveDefinite);
    b = obs_batch(3);
    b.obs[0].r00 = 0.0f;
    rejects(b, Error::kNotPositiveDefinite);
    // Items past count are not validated (they are not sent).
    b = obs_batch(3);
    b.obs[10].range_m = -1.0f;
    rejects(b, Error::kOk);
  }
  SUBCASE("ASSOC_RESULT") {
    AssocResult a = sample<AssocResult>();
    a.pairs[0].feature_id = -3;
    rejects(a, Error::kOutOfRange);
    a = sample<AssocResult>();
    a.pairs[0].d2 = -1.0f;
    rejects(a, Error::kOutOfRange);
    a.pairs[0].d2 = -std::numeric_limits<float>::infinity();
    rejects(a, Error::kNonFinite);
    a.pairs[0].feature_id = std::numeric_limits<std::int32_t>::max();
    a.pairs[0].d2 = 0.0f;
    rejects(a, Error::kOk);
    // The outcome and the id agree: an id only for a pairing or a new landmark.
    a = sample<AssocResult>();
    a.pairs[0].outcome = PairingOutcome::kUnmatched;
    rejects(a, Error::kOutOfRange);
    a = sample<AssocResult>();
    a.pairs[1].outcome = PairingOutcome::kNewLandmark;
    rejects(a, Error::kOutOfRange);
    a = sample<AssocResult>();
    a.pairs[0].outcome = static_cast<PairingOutcome>(5);
    rejects(a, Error::kOutOfRange);
  }
  SUBCASE("POSE, CAPABILITIES, ACK, NACK, ERROR") {
    Pose p = sample<Pose>();
    p.cov_upper[3] = -0.1f;
    rejects(p, Error::kOutOfRange);
    Capabilities c = sample<Capabilities>();
    c.scalar_bytes = 5;
    rejects(c, Error::kOutOfRange);
    c = sample<Capabilities>();
    c.max_groups = 0;
    rejects(c, Error::kOutOfRange);
    c = sample<Capabilities>();
    c.firmware_id[14] = 'x';  // text after the zero padding
    rejects(c, Error::kOutOfRange);
    c = sample<Capabilities>();
    c.firmware_id[0] = '\n';
    rejects(c, Error::kOutOfRange);
    c.set_firmware_id("0123456789abcdefXYZ");  // truncated to 16, no padding: fine
    rejects(c, Error::kOk);
    CHECK(c.firmware_id[15] == 'f');
    Ack a{};
    a.acked_type = 0x55;  // any type number: a stray ACK matches no request
    rejects(a, Error::kOk);
    Nack n = sample<Nack>();
    n.error = Error::kOk;
    rejects(n, Error::kOutOfRange);
    n.error = Error::kIncomplete;
    rejects(n, Error::kOutOfRange);
    n.error = Error::kInternal;
    rejects(n, Error::kOk);
    Bytes pl = payload_of(n);
    pl[3] = kErrorCount;
    Nack out = sample<Nack>();
    CHECK(out.decode(pl.data(), pl.size()) == Error::kOutOfRange);
    CHECK(out.error == sample<Nack>().error);
    ErrorReport er{};
    er.error = Error::kOk;
    rejects(er, Error::kOutOfRange);
  }
}

TEST_CASE("protocol: HELLO version and schema hash") {
  CHECK(kProtocolVersion == 1);
  CHECK(kSchemaHash == fnv1a32(kSchemaText, kSchemaTextLength));
  // Pinned: if this fails, the schema text changed. That is the point: update docs/protocol.md
  // (hash value) and make sure both ends are rebuilt.
  CHECK(kSchemaHash == 0x01445241u);
  Hello h{};
  CHECK(check_hello(h) == Error::kOk);
  h.protocol_version = 2;
  CHECK(check_hello(h) == Error::kBadVersion);
  h = Hello{};
  h.schema_hash ^= 1u;
  CHECK(check_hello(h) == Error::kSchemaMismatch);
  // One character of the text changes the hash.
  std::string text(kSchemaText, kSchemaTextLength);
  text[text.find("OBS_BATCH")] = 'o';
  CHECK(fnv1a32(text.data(), text.size()) != kSchemaHash);
}

TEST_CASE("protocol: SHUTDOWN and CONFIG's periodic STATS on the wire") {
  // CONFIG's last field, after the 39 bytes of the first version.
  const std::vector<Field> cf = schema_fields(MsgType::kConfig);
  REQUIRE(cf.back().name == "stats_period_scans");
  CHECK(cf.back().type == "u16");
  CHECK(cf.back().offset == 39);
  Config c = sample<Config>();
  c.stats_period_scans = 0x0102;
  const Bytes pl = payload_of(c);
  REQUIRE(pl.size() == 41);
  CHECK(pl[39] == 0x02);
  CHECK(pl[40] == 0x01);
  CHECK(Config{}.stats_period_scans == 0);  // off unless asked for
  Config out{};
  REQUIRE(out.decode(pl.data(), pl.size()) == Error::kOk);
  CHECK(out.stats_period_scans == 0x0102);
  CHECK(out.decode(pl.data(), 39) == Error::kBadLength);  // a first-version CONFIG is refused
  // SHUTDOWN: type 0x09, one byte, any exit code.
  CHECK(static_cast<std::uint8_t>(Shutdown::kType) == 0x09);
  CHECK(is_known_type(0x09));
  CHECK(std::string(to_string(MsgType::kShutdown)) == "SHUTDOWN");
  for (int code = 0; code < 256; ++code) {
    Shutdown sd{};
    sd.exit_code = static_cast<std::uint8_t>(code);
    const Bytes b = payload_of(sd);
    REQUIRE(b.size() == 1);
    CHECK(b[0] == code);
    Shutdown back{};
    CHECK(back.decode(b.data(), b.size()) == Error::kOk);
    CHECK(back.exit_code == code);
  }
  Shutdown sd = sample<Shutdown>();
  CHECK(sd.decode(nullptr, 0) == Error::kBadLength);
  const Bytes two = {1, 2};
  CHECK(sd.decode(two.data(), two.size()) == Error::kBadLength);
  CHECK(sd.exit_code == sample<Shutdown>().exit_code);
  // The schema states the session rules a reconnecting host relies on.
  const std::string text(kSchemaText, kSchemaTextLength);
  CHECK(text.find("stream_applied_once_by_seq_since=CONFIG,RESET") != std::string::npos);
  CHECK(text.find("acked=CONFIG,RESET,SHUTDOWN") != std::string::npos);
}

TEST_CASE("protocol: message counters classify rejections") {
  MessageCounters mc;
  for (const Error e : {Error::kOk, Error::kWrongType, Error::kUnknownType, Error::kBadLength, Error::kNonFinite,
                        Error::kOutOfRange, Error::kCapacityExceeded, Error::kNotPositiveDefinite}) {
    mc.record(e);
  }
  CHECK(mc.unknown_type == 1);
  CHECK(mc.invalid_field == 5);
  for (std::uint8_t v = 0; v < kErrorCount; ++v) CHECK(std::string(to_string(static_cast<Error>(v))) != "unknown");
}

TEST_CASE("protocol: frame overhead of a 20-observation OBS_BATCH") {
  const ObsBatch b = obs_batch(20);
  const Bytes pl = payload_of(b);
  const Bytes wire = frame_of(b);
  CHECK(pl.size() == 405);
  CHECK(wire.size() >= 405 + 12 + 1 + 1);              // header + CRC, one COBS code byte, delimiter
  CHECK(wire.size() <= max_wire_size(405));            // 405 + 12 + 2 (COBS worst case) + 1
  CHECK(max_wire_size(405) == 420);
  MESSAGE("20-obs OBS_BATCH: payload " << pl.size() << " B, wire " << wire.size() << " B, overhead "
                                       << wire.size() - pl.size() << " B");
}
