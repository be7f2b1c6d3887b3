// tests/protocol: messages. Round trip of every message, whole and one byte at a time; unknown and
// unexpected types; counts over capacity, exactly full, and len against count; NaN and Inf in every
// float field (offsets taken from the schema text); ranges and positive definiteness; SHUTDOWN and
// CONFIG's periodic STATS; the message counters; the frame overhead of a full scan.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "protocol/protocol_fixtures.hpp"

using namespace proto_test;

TEST_CASE_TEMPLATE("protocol: round trip of every message, whole and one byte at a time", M, Hello, Capabilities,
                   Config, Ack, Nack, Ping, Pong, Reset, Shutdown, Relocalise, SubmapAck, Odometry, OdomDelta, ObsBatch,
                   SubmapSeed, AssocResult, Pose, Submap, SubmapCov, StatsRequest, Stats, ErrorReport) {
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
    if constexpr (M::kItemSize > 0) expected += m.count * s.item_bytes;  // a list's items
    CHECK(payload.size() == expected);
  }
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
  const std::vector<SchemaField> fields = schema_fields(M::kType, count);
  int checked = 0;
  for (const SchemaField& fd : fields) {
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

TEST_CASE("protocol: the CONFIG sample differs from the defaults in every field and is valid") {
  const Config c = sample<Config>();
  const Config d{};
  int fields = 0, differ = 0;
  auto one = [&](const auto& f) {
    CAPTURE(f.name);
    const bool other = !(c.*(f.member) == d.*(f.member));
    CHECK(other);
    ++fields;
    differ += other;
  };
  std::apply([&](const auto&... f) { (one(f), ...); }, Config::fields());
  CHECK(differ == fields);
  CHECK(fields > 0);
  std::array<std::uint8_t, kMaxPayload> buf{};
  std::size_t n = 0;
  CHECK(c.encode(buf.data(), buf.size(), n) == Error::kOk);
}

TEST_CASE("protocol: NaN and Inf in every float field are rejected") {
  check_float_fields(sample<Config>());
  check_float_fields(sample<Reset>());
  check_float_fields(sample<Odometry>());
  check_float_fields(obs_batch(3), 3);
  check_float_fields(sample<AssocResult>(), 4);
  check_float_fields(sample<Pose>());
  check_float_fields(sample<SubmapSeed>(), 3);
  check_float_fields(sample<Submap>(), 4);
  check_float_fields(sample<SubmapCov>(), 3);
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
    c.node_budget = 0;  // the device's capacity
    rejects(c, Error::kOk);
    c = ok;
    c.ambiguity_margin = -0.5f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.seed_min_position_var_m2 = 0.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.rjc_tries = 0;
    rejects(c, Error::kOutOfRange);
    c.rjc_tries = 65;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.occlusion_rad = -0.01f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.static_gate_level = 1.0f;
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
    c.landmark_confirm_nats = 0.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.landmark_delete_nats = 0.0f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.landmark_reserve_nats = 0.0f;
    rejects(c, Error::kOk);
    c.landmark_reserve_nats = -0.01f;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.max_tentative_reviews = 0;
    rejects(c, Error::kOutOfRange);
    c = ok;
    c.groups = 0;  // 0: chosen by BIC
    rejects(c, Error::kOk);
    // Wire-only values: strategy 7 (one past PCJCBB) and condition_groups 2.
    Bytes pl = payload_of(ok);
    Config out = ok;
    pl[0] = 6;  // PCJCBB
    CHECK(out.decode(pl.data(), pl.size()) == Error::kOk);
    pl[0] = 7;
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
  SUBCASE("SUBMAP_SEED") {
    SubmapSeed s = submap_seed(static_cast<int>(kSeedsPerFrame));
    rejects(s, Error::kOk);
    s.items[7].p01 = 0.6f;  // p00 p11 < p01^2
    rejects(s, Error::kNotPositiveDefinite);
    s = submap_seed(2);
    s.items[1].p11 = 0.0f;
    rejects(s, Error::kNotPositiveDefinite);
    s.items[1].p11 = 0.5f;
    s.items[1].x_m = std::numeric_limits<float>::infinity();
    rejects(s, Error::kNonFinite);
    s.items[1].x_m = 1.0f;
    s.items[1].exist_nats = std::numeric_limits<float>::quiet_NaN();  // the global map's log-odds
    rejects(s, Error::kNonFinite);
    s = submap_seed(static_cast<int>(kSeedsPerFrame));
    s.count = static_cast<std::uint8_t>(kSeedsPerFrame + 1);
    rejects(s, Error::kCapacityExceeded);
    CHECK(payload_of(submap_seed(static_cast<int>(kSeedsPerFrame))).size() == 9 + 8 * 24);
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
    p = sample<Pose>();
    p.ids[1].feature_id = -1;  // an id is >= 0
    rejects(p, Error::kOutOfRange);
    p = sample<Pose>();
    p.removed = 3;  // three removed, two named: the list must name min(removed, 8)
    rejects(p, Error::kOutOfRange);
    p.removed = 30;  // more than a POSE names: the first 8, counted
    p.count = 8;
    for (std::size_t k = 0; k < kRemovedPerPose; ++k) p.ids[k].feature_id = static_cast<std::int32_t>(k);
    rejects(p, Error::kOk);
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

TEST_CASE("protocol: SHUTDOWN and CONFIG's periodic STATS on the wire") {
  // CONFIG's last field, after the 168 bytes of the step's options.
  const std::vector<SchemaField> cf = schema_fields(MsgType::kConfig);
  REQUIRE(cf.back().name == "stats_period_scans");
  CHECK(cf.back().type == "u16");
  CHECK(cf.back().offset == 168);
  Config c = sample<Config>();
  c.stats_period_scans = 0x0102;
  const Bytes pl = payload_of(c);
  REQUIRE(pl.size() == 170);
  CHECK(pl[168] == 0x02);
  CHECK(pl[169] == 0x01);
  CHECK(Config{}.stats_period_scans == 0);  // off unless asked for
  Config out{};
  REQUIRE(out.decode(pl.data(), pl.size()) == Error::kOk);
  CHECK(out.stats_period_scans == 0x0102);
  CHECK(out.decode(pl.data(), 77) == Error::kBadLength);
  CHECK(out.decode(pl.data(), 41) == Error::kBadLength);  // a CONFIG of the 16-field schema is refused
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
  CHECK(wire.size() >= 405 + 12 + 1 + 1);    // header + CRC, one COBS code byte, delimiter
  CHECK(wire.size() <= max_wire_size(405));  // 405 + 12 + 2 (COBS worst case) + 1
  CHECK(max_wire_size(405) == 420);
  MESSAGE("20-obs OBS_BATCH: payload " << pl.size() << " B, wire " << wire.size() << " B, overhead "
                                       << wire.size() - pl.size() << " B");
}
