// tests/protocol: frames and the byte-at-a-time Decoder. The golden PING frame (little-endian header
// and fields), the largest payload and the encoder's buffer bounds, every truncation point and every
// single-bit flip of small frames (counted exactly, against a reference model of the checks),
// garbage, empty and oversize frames, the len field, version and flags.
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
  CHECK(ap[14] == 2);                                                               // pairs[1].outcome
  CHECK(Bytes(ap.begin() + 15, ap.begin() + 19) == Bytes{0xFF, 0xFF, 0xFF, 0xFF});  // pairs[1].feature_id = -1
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
  for (const auto& named : frames) {
    const char* const name = named.first;  // a variable, not a binding: CAPTURE's lambda takes it
    const Bytes& wire = named.second;
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
    const Feed r =
        feed(d, raw_frame(1, static_cast<std::uint8_t>(bit | 0x01), odo, 9, static_cast<std::uint16_t>(pl.size()), pl));
    CHECK(r.frames.empty());
    REQUIRE(r.errors.size() == 1);
    CHECK(r.errors[0] == Error::kBadFlags);
    ++dropped;
  }
  CHECK(d.counters().bad_flags == dropped);
  CHECK(dropped == 4);
}
