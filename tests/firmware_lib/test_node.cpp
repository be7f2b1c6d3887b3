// The device loop in process: a whole session (HELLO, CONFIG, RESET, ODOMETRY, OBS_BATCH, STATS) fed
// as bytes allocates nothing, and every reply is a valid frame of the expected type.
#include <doctest/doctest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <vector>

#include "geojcbb/node/node.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;
using geojcbb::test::allocations_during;

namespace {
struct Sink {
  std::vector<std::uint8_t> bytes;
};
template <class M>
void append(std::vector<std::uint8_t>& out, const M& m, std::uint16_t seq) {
  proto::EncodedFrame f;
  REQUIRE(proto::encode_message(m, seq, 0, f) == proto::Error::kOk);
  out.insert(out.end(), f.bytes.begin(), f.bytes.begin() + static_cast<std::ptrdiff_t>(f.size));
}
}  // namespace

TEST_CASE("node: a session fed as bytes allocates nothing and answers every request") {
  using NB = Bounds<24, 32, 5, 4000, 64>;
  auto node = std::make_unique<node::Node<float, NB>>();
  auto sink = std::make_unique<Sink>();
  sink->bytes.reserve(1 << 16);  // the sink's own growth is not the node's
  node->start(node::Output{sink.get(),
                           [](void* c, const std::uint8_t* p, std::size_t n) {
                             auto& b = static_cast<Sink*>(c)->bytes;
                             b.insert(b.end(), p, p + n);
                           }},
              42);
  std::vector<std::uint8_t> in;
  std::uint16_t seq = 0;
  append(in, proto::Hello{}, seq++);
  proto::Config c;
  c.local_radius_m = 12.0f;
  c.max_range_m = 10.0f;
  append(in, c, seq++);
  append(in, proto::Reset{}, seq++);
  for (int k = 0; k < 20; ++k) {
    proto::Odometry o;
    o.v_mps = 0.5f;
    o.dt_s = 0.1f;
    o.sigma_v_mps = 0.05f;
    o.sigma_w_radps = 0.01f;
    append(in, o, seq++);
    proto::ObsBatchT<24> b;
    b.batch_id = static_cast<std::uint32_t>(k);
    b.count = 3;
    for (int i = 0; i < 3; ++i) {
      b.obs[static_cast<std::size_t>(i)] = proto::ObservationWire{5.0f - 0.05f * k, -0.6f + 0.6f * i, 0.01f, 0.0f, 3e-4f};
    }
    append(in, b, seq++);
  }
  append(in, proto::StatsRequest{}, seq++);
  CHECK(allocations_during([&] { node->on_bytes(in.data(), in.size()); }) == 0);
  // Replies: CAPABILITIES, ACK, ACK, 20 x (ASSOC_RESULT, POSE), STATS.
  proto::Decoder dec;
  std::vector<std::uint8_t> types;
  for (std::uint8_t byte : sink->bytes) {
    proto::FrameView f;
    if (dec.push(byte, f) == proto::Error::kOk) types.push_back(f.type);
  }
  REQUIRE(types.size() == 44);
  CHECK(types[0] == static_cast<std::uint8_t>(proto::MsgType::kCapabilities));
  CHECK(types[1] == static_cast<std::uint8_t>(proto::MsgType::kAck));
  CHECK(types[2] == static_cast<std::uint8_t>(proto::MsgType::kAck));
  for (int k = 0; k < 20; ++k) {
    CHECK(types[static_cast<std::size_t>(3 + 2 * k)] == static_cast<std::uint8_t>(proto::MsgType::kAssocResult));
    CHECK(types[static_cast<std::size_t>(4 + 2 * k)] == static_cast<std::uint8_t>(proto::MsgType::kPose));
  }
  CHECK(types[43] == static_cast<std::uint8_t>(proto::MsgType::kStats));
  CHECK(node->stats().scans == 20);
  CHECK(node->slam_step().slam().landmarks() >= 3);  // the side points are not a rigid scene: some re-mapped
}

// A lossy channel between host and device: drops, duplicates, reordering, single-bit flips and
// garbage bursts, at set rates over 12,000 frames. Every corrupted frame is rejected and counted,
// the counters equal the injected faults, no good frame is lost, and the device keeps answering.
TEST_CASE("node: a lossy channel over 12,000 frames: faults counted exactly, no good frame lost") {
  using NB = Bounds<24, 32, 5, 4000, 64>;
  auto node = std::make_unique<node::Node<float, NB>>();
  auto sink = std::make_unique<Sink>();
  node->start(node::Output{sink.get(),
                           [](void* c, const std::uint8_t* p, std::size_t n) {
                             auto& b = static_cast<Sink*>(c)->bytes;
                             b.insert(b.end(), p, p + n);
                           }},
              1);
  constexpr int kFrames = 12000;
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<std::vector<std::uint8_t>> frames;
  for (int i = 0; i < kFrames; ++i) {
    proto::Ping p;
    p.nonce = static_cast<std::uint32_t>(i);
    std::vector<std::uint8_t> f;
    append(f, p, static_cast<std::uint16_t>(i));
    frames.push_back(f);
  }
  std::vector<std::uint8_t> wire;
  std::vector<int> expected(kFrames, 0);  // PONGs expected per nonce
  int drops = 0, dups = 0, swaps = 0, flips = 0, bursts = 0, good = 0;
  for (int i = 0; i < kFrames; ++i) {
    if (i + 1 < kFrames && u(rng) < 0.02) {  // reorder: send the next frame first
      std::swap(frames[static_cast<std::size_t>(i)], frames[static_cast<std::size_t>(i + 1)]);
      ++swaps;
    }
    std::vector<std::uint8_t> f = frames[static_cast<std::size_t>(i)];
    proto::Decoder peek;  // which nonce this frame carries
    proto::FrameView v;
    std::uint32_t nonce = 0;
    for (std::uint8_t b : f)
      if (peek.push(b, v) == proto::Error::kOk) nonce = proto::get_u32_le(v.payload);
    const double r = u(rng);
    if (r < 0.03) {  // drop
      ++drops;
      continue;
    }
    if (r < 0.06) {  // one bit flipped in a data byte, never making a 0x00 (that would split the frame)
      std::size_t at;
      std::uint8_t flipped;
      do {
        at = static_cast<std::size_t>(u(rng) * static_cast<double>(f.size() - 1));
        flipped = static_cast<std::uint8_t>(f[at] ^ (1u << static_cast<unsigned>(u(rng) * 8)));
      } while (flipped == 0);
      f[at] = flipped;
      ++flips;
    } else {
      ++expected[nonce];
      ++good;
      if (r < 0.09) {  // duplicate
        wire.insert(wire.end(), f.begin(), f.end());
        ++expected[nonce];
        ++dups;
      }
    }
    wire.insert(wire.end(), f.begin(), f.end());
    if (u(rng) < 0.02) {  // a burst of line noise, ended by a delimiter
      const int n = 1 + static_cast<int>(u(rng) * 40);
      for (int k = 0; k < n; ++k) wire.push_back(static_cast<std::uint8_t>(1 + u(rng) * 254));
      wire.push_back(0);
      ++bursts;
    }
  }
  // Fed in uneven chunks, as a UART driver would.
  for (std::size_t at = 0; at < wire.size();) {
    const std::size_t n = std::min<std::size_t>(wire.size() - at, 1 + static_cast<std::size_t>(u(rng) * 300));
    node->on_bytes(wire.data() + at, n);
    at += n;
  }
  std::vector<int> got(kFrames, 0);
  proto::Decoder dec;
  for (std::uint8_t b : sink->bytes) {
    proto::FrameView f;
    if (dec.push(b, f) != proto::Error::kOk) continue;
    REQUIRE(f.type == static_cast<std::uint8_t>(proto::MsgType::kPong));
    proto::Pong p;
    REQUIRE(p.decode(f.payload, f.len) == proto::Error::kOk);
    ++got[p.nonce];
  }
  CHECK(got == expected);  // every good frame answered, as often as it was sent; nothing else
  const proto::Stats st = node->stats();
  CHECK(st.frames_ok == static_cast<std::uint32_t>(good + dups));
  CHECK(st.bad_crc + st.bad_length + st.overrun == static_cast<std::uint32_t>(flips + bursts));
  CHECK(st.unknown_type == 0);
  CHECK(st.invalid_field == 0);
  MESSAGE("frames " << kFrames << ": dropped " << drops << ", duplicated " << dups << ", reordered " << swaps
                    << ", bit flips " << flips << ", bursts " << bursts << "; bad CRC " << st.bad_crc
                    << ", bad length " << st.bad_length << ", overrun " << st.overrun);
  CHECK(drops > 200);
  CHECK(flips > 200);
  CHECK(bursts > 100);
  // Not stuck: one more PING is answered.
  sink->bytes.clear();
  std::vector<std::uint8_t> one;
  append(one, proto::Ping{}, 1);
  node->on_bytes(one.data(), one.size());
  CHECK(!sink->bytes.empty());
}
