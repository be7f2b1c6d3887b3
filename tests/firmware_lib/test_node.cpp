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
      b.obs[static_cast<std::size_t>(i)] = proto::ObservationWire{
          5.0f - 0.05f * static_cast<float>(k), -0.6f + 0.6f * static_cast<float>(i), 0.01f, 0.0f, 3e-4f};
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
      std::swap(frames[static_cast<std::size_t>(i)], frames[static_cast<std::size_t>(i) + 1]);
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
                    << ", bit flips " << flips << ", bursts " << bursts << "; bad CRC " << st.bad_crc << ", bad length "
                    << st.bad_length << ", overrun " << st.overrun);
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

namespace {
using NodeB = Bounds<24, 32, 5, 4000, 64>;
struct Reply {
  std::uint8_t type;
  std::vector<std::uint8_t> payload;
};
std::vector<Reply> replies(const std::vector<std::uint8_t>& bytes) {
  std::vector<Reply> out;
  proto::Decoder dec;
  for (std::uint8_t b : bytes) {
    proto::FrameView f;
    if (dec.push(b, f) == proto::Error::kOk) {
      out.push_back({f.type, std::vector<std::uint8_t>(f.payload, f.payload + f.len)});
    }
  }
  return out;
}
template <class M>
M decoded(const Reply& r) {
  M m{};
  REQUIRE(r.type == static_cast<std::uint8_t>(M::kType));
  REQUIRE(m.decode(r.payload.data(), r.payload.size()) == proto::Error::kOk);
  return m;
}
proto::Odometry test_odometry() {
  proto::Odometry o;
  o.v_mps = 0.5f;
  o.dt_s = 0.1f;
  o.sigma_v_mps = 0.05f;
  o.sigma_w_radps = 0.01f;
  return o;
}
proto::ObsBatchT<24> test_batch(int k) {
  proto::ObsBatchT<24> b;
  b.batch_id = static_cast<std::uint32_t>(100 + k);
  b.count = 3;
  for (int i = 0; i < 3; ++i) {
    b.obs[static_cast<std::size_t>(i)] = proto::ObservationWire{
        5.0f - 0.05f * static_cast<float>(k), -0.6f + 0.6f * static_cast<float>(i), 0.01f, 0.0f, 3e-4f};
  }
  return b;
}
struct Harness {
  std::unique_ptr<node::Node<float, NodeB>> node = std::make_unique<node::Node<float, NodeB>>();
  std::vector<std::uint8_t> out;
  std::vector<int> shutdowns;  // exit codes, in call order
  std::size_t out_at_shutdown = 0;
  std::uint16_t seq = 0;
  explicit Harness(bool with_hook = true) {
    node->start(node::Output{this,
                             [](void* c, const std::uint8_t* p, std::size_t n) {
                               auto& b = static_cast<Harness*>(c)->out;
                               b.insert(b.end(), p, p + n);
                             },
                             with_hook ? +[](void* c, std::uint8_t code) {
                               auto* h = static_cast<Harness*>(c);
                               h->shutdowns.push_back(code);
                               h->out_at_shutdown = h->out.size();
                             }
                                       : nullptr},
                7);
  }
  template <class M>
  std::vector<std::uint8_t> frame(const M& m, std::uint16_t at) {
    std::vector<std::uint8_t> f;
    append(f, m, at);
    return f;
  }
  template <class M>
  void send(const M& m) {
    const std::vector<std::uint8_t> f = frame(m, seq++);
    node->on_bytes(f.data(), f.size());
  }
  void send_bytes(const std::vector<std::uint8_t>& f) { node->on_bytes(f.data(), f.size()); }
  void open(std::uint16_t stats_period) {
    send(proto::Hello{});
    proto::Config c;
    c.local_radius_m = 12.0f;
    c.max_range_m = 10.0f;
    c.stats_period_scans = stats_period;
    send(c);
    send(proto::Reset{});
  }
};
}  // namespace

TEST_CASE("node: periodic STATS after the POSE of every N-th scan since CONFIG or RESET") {
  for (const std::uint16_t period : {std::uint16_t{0}, std::uint16_t{1}, std::uint16_t{3}, std::uint16_t{7}}) {
    CAPTURE(period);
    Harness h;
    h.open(period);
    for (int k = 0; k < 10; ++k) {
      h.send(test_odometry());
      h.send(test_batch(k));
    }
    h.send(proto::Reset{});  // a new run: the count starts again
    for (int k = 10; k < 14; ++k) {
      h.send(test_odometry());
      h.send(test_batch(k));
    }
    const std::vector<Reply> r = replies(h.out);
    // CAPABILITIES, ACK, ACK, then per scan ASSOC_RESULT, POSE [, STATS]; an ACK for the second RESET.
    std::size_t at = 3;
    int stats_seen = 0;
    for (int k = 0; k < 14; ++k) {
      if (k == 10) CHECK(r.at(at++).type == static_cast<std::uint8_t>(proto::MsgType::kAck));
      CHECK(decoded<proto::AssocResultT<24>>(r.at(at++)).batch_id == static_cast<std::uint32_t>(100 + k));
      CHECK(decoded<proto::Pose>(r.at(at++)).batch_id == static_cast<std::uint32_t>(100 + k));
      const int in_run = k < 10 ? k + 1 : k - 9;
      if (period != 0 && in_run % period == 0) {
        const proto::Stats st = decoded<proto::Stats>(r.at(at++));
        CHECK(st.scans == static_cast<std::uint32_t>(k + 1));  // sent after this scan
        ++stats_seen;
      }
    }
    CHECK(at == r.size());  // nothing else
    CHECK(stats_seen == (period == 0 ? 0 : 10 / period + 4 / period));
  }
}

TEST_CASE("node: SHUTDOWN is acknowledged, then calls the board's hook once with the exit code") {
  SUBCASE("not before HELLO") {
    Harness h;
    proto::Shutdown sd;
    sd.exit_code = 5;
    h.send(sd);
    CHECK(h.shutdowns.empty());
    const std::vector<Reply> r = replies(h.out);
    REQUIRE(r.size() == 1);
    const proto::ErrorReport e = decoded<proto::ErrorReport>(r[0]);
    CHECK(e.error == proto::Error::kNotReady);
    CHECK(e.offending_type == 0x09);
  }
  SUBCASE("after HELLO: ACK first, then the hook") {
    Harness h;
    h.send(proto::Hello{});
    proto::Shutdown sd;
    sd.exit_code = 42;
    const std::uint16_t seq = h.seq;
    h.send(sd);
    REQUIRE(h.shutdowns.size() == 1);
    CHECK(h.shutdowns[0] == 42);
    const std::vector<Reply> r = replies(h.out);
    REQUIRE(r.size() == 2);  // CAPABILITIES, ACK
    const proto::Ack a = decoded<proto::Ack>(r[1]);
    CHECK(a.acked_type == 0x09);
    CHECK(a.acked_seq == seq);
    CHECK(h.out_at_shutdown == h.out.size());  // the ACK was written before the hook ran
  }
  SUBCASE("without a hook it is only acknowledged") {
    Harness h(false);
    h.send(proto::Hello{});
    h.send(proto::Shutdown{});
    const std::vector<Reply> r = replies(h.out);
    REQUIRE(r.size() == 2);
    CHECK(decoded<proto::Ack>(r[1]).acked_type == 0x09);
    h.send(proto::Ping{});  // still serving
    CHECK(replies(h.out).size() == 3);
  }
  SUBCASE("a bad payload length is refused and counted, no hook") {
    Harness h;
    h.send(proto::Hello{});
    const std::uint8_t two[2] = {1, 2};
    proto::EncodedFrame f;
    REQUIRE(proto::encode_frame(0x09, 9, 0, two, 2, f.bytes.data(), f.bytes.size(), f.size) == proto::Error::kOk);
    h.node->on_bytes(f.bytes.data(), f.size);
    CHECK(h.shutdowns.empty());
    CHECK(h.node->stats().invalid_field == 1);
  }
}

TEST_CASE("node: retransmitted stream frames are not applied twice, and the last batch's replies come again") {
  // Reference: every frame once.
  Harness ref;
  ref.open(0);
  std::vector<std::vector<std::uint8_t>> odo, bat;
  Harness h;
  h.open(0);
  REQUIRE(h.seq == ref.seq);
  for (int k = 0; k < 6; ++k) {
    odo.push_back(h.frame(test_odometry(), static_cast<std::uint16_t>(h.seq + 2 * k)));
    bat.push_back(h.frame(test_batch(k), static_cast<std::uint16_t>(h.seq + 2 * k + 1)));
    ref.send_bytes(odo.back());
    ref.send_bytes(bat.back());
  }
  // The device: scans 0 and 1, then scan 2 whose replies "were lost"; the host resends scan 2's
  // ODOMETRY and OBS_BATCH with their original seq, then goes on.
  for (int k = 0; k < 3; ++k) {
    h.send_bytes(odo[static_cast<std::size_t>(k)]);
    h.send_bytes(bat[static_cast<std::size_t>(k)]);
  }
  const std::size_t before = replies(h.out).size();
  h.send_bytes(odo[2]);
  h.send_bytes(bat[2]);
  const std::vector<Reply> again = replies(h.out);
  REQUIRE(again.size() == before + 2);  // the stored ASSOC_RESULT and POSE, not a second step
  CHECK(again[before].payload == again[before - 2].payload);
  CHECK(again[before + 1].payload == again[before - 1].payload);
  CHECK(h.node->stats().scans == 3);
  // A retransmission of an older batch (not the last) is neither applied nor answered.
  h.send_bytes(odo[1]);
  h.send_bytes(bat[1]);
  CHECK(replies(h.out).size() == before + 2);
  for (int k = 3; k < 6; ++k) {
    h.send_bytes(odo[static_cast<std::size_t>(k)]);
    h.send_bytes(bat[static_cast<std::size_t>(k)]);
  }
  CHECK(h.node->stats().scans == 6);
  // Every fresh reply equals the reference's: the state never saw the duplicates.
  std::vector<Reply> got = replies(h.out), want = replies(ref.out);
  got.erase(got.begin() + static_cast<std::ptrdiff_t>(before), got.begin() + static_cast<std::ptrdiff_t>(before + 2));
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    CHECK(got[i].type == want[i].type);
    CHECK(got[i].payload == want[i].payload);
  }
  // After RESET the sequence starts afresh: an old seq is a new run's first frame.
  h.send(proto::Reset{});
  const std::size_t n = replies(h.out).size();
  h.send_bytes(odo[0]);
  h.send_bytes(bat[0]);
  CHECK(replies(h.out).size() == n + 2);
  CHECK(h.node->stats().scans == 7);
}

TEST_CASE("node: stream frames stay fresh across the 16-bit seq wrap and long runs of control frames") {
  // Seq starts just below the wrap; between scans the host sends 40,000 PINGs (more than half the
  // seq space), as an idle host polling would. Every scan must still be applied and answered, and a
  // retransmission of the last batch must still be recognised.
  Harness h;
  h.seq = 0xFFF0;
  h.open(0);
  for (int k = 0; k < 4; ++k) {
    const std::size_t n = replies(h.out).size();
    h.send(test_odometry());
    const std::vector<std::uint8_t> batch = h.frame(test_batch(k), h.seq++);
    h.send_bytes(batch);
    REQUIRE(replies(h.out).size() == n + 2);  // ASSOC_RESULT, POSE
    CHECK(h.node->stats().scans == static_cast<std::uint32_t>(k + 1));
    h.send_bytes(batch);  // a retransmission right away: answered from the stored reply, not applied
    CHECK(replies(h.out).size() == n + 4);
    CHECK(h.node->stats().scans == static_cast<std::uint32_t>(k + 1));
    proto::Ping p;
    for (int i = 0; i < 40000; ++i) h.send(p);
  }
  // Only the PONGs besides: no ERROR, nothing dropped.
  std::size_t errors = 0;
  for (const Reply& r : replies(h.out)) errors += r.type == static_cast<std::uint8_t>(proto::MsgType::kError);
  CHECK(errors == 0);
}

TEST_CASE("node: ODOM_DELTA predicts with the increment and its covariance; a bad covariance is refused") {
  // The device applies a pose increment exactly as SlamStep::predict(PoseIncrement) does in process
  // (the same float arithmetic), once per seq; a covariance that is not positive semi-definite is
  // an ERROR and changes nothing.
  using NB = DefaultBounds;
  auto node = std::make_unique<node::Node<float, NB>>();
  std::vector<std::uint8_t> sink;
  node->start(node::Output{&sink,
                           [](void* c, const std::uint8_t* p, std::size_t n) {
                             auto& b = *static_cast<std::vector<std::uint8_t>*>(c);
                             b.insert(b.end(), p, p + n);
                           }},
              7);
  auto feed = [&](const auto& m, std::uint16_t seq) {
    proto::EncodedFrame f;
    REQUIRE(proto::encode_message(m, seq, 0, f) == proto::Error::kOk);
    node->on_bytes(f.bytes.data(), f.size);
  };
  feed(proto::Hello{}, 0);
  feed(proto::Config{}, 1);
  feed(proto::Reset{}, 2);
  auto ref = std::make_unique<node::SlamStep<float, NB>>();
  REQUIRE(ref->configure(node::StepSettings<float>{}) == Status::kOk);
  REQUIRE(ref->reset(node->slam_step().slam().pose(), node->slam_step().slam().pose_covariance()) == Status::kOk);
  proto::OdomDelta d;
  d.dx_m = 0.5f;
  d.dy_m = 0.125f;
  d.dtheta_rad = 0.0625f;
  d.cov_upper = {1e-3f, 1e-5f, 0.0f, 5e-4f, 1e-6f, 2e-4f};
  feed(d, 3);
  Mat3<float> C;
  C << 1e-3f, 1e-5f, 0.0f, 1e-5f, 5e-4f, 1e-6f, 0.0f, 1e-6f, 2e-4f;
  REQUIRE(ref->predict(ekf::PoseIncrement<float>{0.5f, 0.125f, 0.0625f, C}) == Status::kOk);
  const Pose2<float> x = node->slam_step().slam().pose();
  CHECK(x.x == ref->slam().pose().x);
  CHECK(x.y == ref->slam().pose().y);
  CHECK(x.theta == ref->slam().pose().theta);
  CHECK(node->slam_step().slam().pose_covariance() == ref->slam().pose_covariance());
  feed(d, 3);  // a retransmission: not applied twice
  CHECK(node->slam_step().slam().pose().x == x.x);
  const std::uint32_t invalid_before = node->stats().invalid_field;
  d.cov_upper = {1e-3f, 0.0f, 0.0f, -1e-3f, 0.0f, 1e-4f};  // a negative variance
  feed(d, 4);
  CHECK(node->slam_step().slam().pose().x == x.x);
  CHECK(node->slam_step().slam().pose_covariance() == ref->slam().pose_covariance());
  CHECK(node->stats().invalid_field == invalid_before + 1);
}

// ---------------------------------------------------------------------------------------------
// The hand-over of a closed local map (docs/submaps.md).

namespace {
/// HELLO, CONFIG (the map closes after `scans` scans), RESET; the replies dropped.
void open_submaps(Harness& h, std::uint32_t scans) {
  h.send(proto::Hello{});
  proto::Config c;
  c.local_radius_m = 12.0f;
  c.max_range_m = 10.0f;
  c.submap_scans = scans;
  h.send(c);
  h.send(proto::Reset{});
  h.out.clear();
}
/// The replies from `at` on that belong to map `id`'s frames, as the host assembles them.
struct Handed {
  int frames = 0;
  std::vector<proto::SubmapLandmarkWire> landmarks;
  std::vector<float> cov;
  float x = 0, y = 0, theta = 0;
};
Handed assemble(const std::vector<Reply>& r, std::size_t at, std::size_t frames, std::uint32_t id) {
  Handed h;
  for (std::size_t k = at; k < at + frames; ++k) {
    REQUIRE(k < r.size());
    if (r[k].type == static_cast<std::uint8_t>(proto::MsgType::kSubmap)) {
      const auto m = decoded<proto::Submap>(r[k]);
      CHECK(m.map_id == id);
      CHECK(m.chunk == k - at);
      CHECK(m.chunks == frames);
      h.landmarks.resize(m.landmarks);
      for (std::size_t i = 0; i < m.count; ++i) h.landmarks[m.first + i] = m.items[i];
      h.x = m.x_m;
      h.y = m.y_m;
      h.theta = m.theta_rad;
    } else {
      const auto m = decoded<proto::SubmapCov>(r[k]);
      CHECK(m.map_id == id);
      CHECK(m.chunk == k - at);
      CHECK(m.offset == h.cov.size());  // in order, none missing
      for (std::size_t i = 0; i < m.count; ++i) h.cov.push_back(m.items[i].v);
    }
    ++h.frames;
  }
  return h;
}
proto::Error error_of(const Reply& r) { return decoded<proto::ErrorReport>(r).error; }
}  // namespace

TEST_CASE("node: a closed local map is handed over whole from the filter, and the next begins only after SUBMAP_ACK") {
  Harness h;
  open_submaps(h, 6);
  for (int k = 0; k < 6; ++k) {
    h.send(test_odometry());
    h.send(test_batch(k));
  }
  const ekf::Slam<float, NodeB>& s = h.node->slam_step().slam();
  std::vector<Reply> r = replies(h.out);
  // 6 x (ASSOC_RESULT, POSE); the sixth POSE announces the frames, which follow at once.
  const auto pose = decoded<proto::Pose>(r.at(11));
  for (int k = 0; k < 5; ++k) CHECK(decoded<proto::Pose>(r.at(static_cast<std::size_t>(2 * k + 1))).submap_frames == 0);
  const int n = s.landmarks();
  REQUIRE(n >= 3);
  REQUIRE(pose.submap_frames == proto::submap_frames(static_cast<std::uint32_t>(n)));
  REQUIRE(r.size() == 12 + pose.submap_frames);
  const Handed m = assemble(r, 12, pose.submap_frames, 0);
  // Everything the filter holds, bit for bit (float on both sides): no second copy was made.
  REQUIRE(static_cast<int>(m.landmarks.size()) == n);
  CHECK(m.x == s.x(0));
  CHECK(m.y == s.x(1));
  CHECK(m.theta == s.x(2));
  for (int j = 0; j < n; ++j) {
    CHECK(m.landmarks[static_cast<std::size_t>(j)].id == s.id(j));
    CHECK(m.landmarks[static_cast<std::size_t>(j)].x_m == s.landmark(j).x());
    CHECK(m.landmarks[static_cast<std::size_t>(j)].y_m == s.landmark(j).y());
    CHECK(m.landmarks[static_cast<std::size_t>(j)].confirmed == s.confirmed(j));
  }
  const int d = s.dim();
  REQUIRE(m.cov.size() == proto::submap_cov_entries(static_cast<std::uint32_t>(n)));
  for (int c = 0; c < d; ++c) {
    for (int q = 0; q <= c; ++q) {
      CHECK(m.cov[static_cast<std::size_t>(c * (c + 1) / 2 + q)] == s.cov(q, c));
      CHECK(ekf::Slam<float, NodeB>::packed_index(q, c) == static_cast<std::size_t>(c * (c + 1) / 2 + q));
    }
  }

  // Until SUBMAP_ACK: stream frames are refused (busy) and not applied.
  const Pose2<float> before = s.pose();
  const std::uint32_t scans = h.node->stats().scans;
  const std::uint16_t odo_seq = h.seq;
  h.out.clear();
  h.send(test_odometry());
  h.send(test_batch(6));
  r = replies(h.out);
  REQUIRE(r.size() == 2);
  CHECK(error_of(r[0]) == proto::Error::kBusy);
  CHECK(error_of(r[1]) == proto::Error::kBusy);
  CHECK(s.pose().x == before.x);
  CHECK(h.node->stats().scans == scans);
  CHECK(s.landmarks() == n);

  // A wrong map id is refused; asked again, the same map comes again, from the same memory.
  h.out.clear();
  proto::SubmapAck wrong;
  wrong.map_id = 1;
  h.send(wrong);
  r = replies(h.out);
  REQUIRE(r.size() == 1);
  CHECK(decoded<proto::Nack>(r[0]).error == proto::Error::kOutOfRange);
  h.out.clear();
  h.out.reserve(1 << 20);  // the sink's own growth is not the node's
  proto::SubmapAck again;
  again.send = true;
  const std::vector<std::uint8_t> again_frame = h.frame(again, h.seq++);
  CHECK(test::allocations_during([&] { h.send_bytes(again_frame); }) == 0);
  r = replies(h.out);
  REQUIRE(r.size() == 1 + pose.submap_frames);
  CHECK(decoded<proto::Ack>(r[0]).acked_type == static_cast<std::uint8_t>(proto::MsgType::kSubmapAck));
  const Handed m2 = assemble(r, 1, pose.submap_frames, 0);
  CHECK(m2.cov == m.cov);
  CHECK(m2.landmarks.size() == m.landmarks.size());

  // SUBMAP_ACK: the next map begins at the robot (its origin), with the landmarks in view carried.
  h.out.clear();
  h.send(proto::SubmapAck{});
  r = replies(h.out);
  REQUIRE(r.size() == 1);
  CHECK(decoded<proto::Ack>(r[0]).acked_type == static_cast<std::uint8_t>(proto::MsgType::kSubmapAck));
  CHECK(s.x(0) == 0.0f);
  CHECK(s.x(1) == 0.0f);
  CHECK(s.x(2) == 0.0f);
  CHECK(s.landmarks() <= n);
  for (int j = 0; j < s.landmarks(); ++j) {  // the carried ones keep their ids, and SUBMAP named them
    bool found = false;
    for (const auto& l : m.landmarks) found = found || (l.id == s.id(j) && l.carried);
    CHECK(found);
  }
  int named = 0;  // and named no other
  for (const auto& l : m.landmarks) named += l.carried;
  CHECK(named == s.landmarks());
  // The refused frames, sent again with their own seq, are applied now; the ACK repeated is harmless.
  h.out.clear();
  h.send_bytes(h.frame(test_odometry(), odo_seq));
  h.send_bytes(h.frame(test_batch(6), static_cast<std::uint16_t>(odo_seq + 1)));
  r = replies(h.out);
  REQUIRE(r.size() == 2);
  CHECK(decoded<proto::AssocResultT<24>>(r[0]).batch_id == 106);
  CHECK(decoded<proto::Pose>(r[1]).submap_frames == 0);
  CHECK(h.node->stats().scans == scans + 1);
  h.out.clear();
  h.send(proto::SubmapAck{});
  r = replies(h.out);
  REQUIRE(r.size() == 1);
  CHECK(r[0].type == static_cast<std::uint8_t>(proto::MsgType::kAck));
}

TEST_CASE("node: a hand-over survives a reconnection (HELLO) and is dropped by RESET; the host may close a map") {
  Harness h;
  open_submaps(h, 4);
  for (int k = 0; k < 4; ++k) {
    h.send(test_odometry());
    h.send(test_batch(k));
  }
  const ekf::Slam<float, NodeB>& s = h.node->slam_step().slam();
  const int n = s.landmarks();
  const std::uint32_t frames = proto::submap_frames(static_cast<std::uint32_t>(n));
  REQUIRE(replies(h.out).size() == 8 + frames);

  SUBCASE("a reconnection keeps the pending map: still busy, and it can be asked for again") {
    h.out.clear();
    h.send(proto::Hello{});
    h.send(test_odometry());
    proto::SubmapAck again;
    again.send = true;
    h.send(again);
    const std::vector<Reply> r = replies(h.out);
    REQUIRE(r.size() == 3 + frames);
    CHECK(r[0].type == static_cast<std::uint8_t>(proto::MsgType::kCapabilities));
    CHECK(error_of(r[1]) == proto::Error::kBusy);
    CHECK(r[2].type == static_cast<std::uint8_t>(proto::MsgType::kAck));
    CHECK(static_cast<int>(assemble(r, 3, frames, 0).landmarks.size()) == n);
  }
  SUBCASE("RESET drops it: stream frames are taken, and no map is pending") {
    h.out.clear();
    h.send(proto::Reset{});
    h.send(test_odometry());
    h.send(test_batch(4));
    h.send(proto::SubmapAck{});
    const std::vector<Reply> r = replies(h.out);
    REQUIRE(r.size() == 4);
    CHECK(r[0].type == static_cast<std::uint8_t>(proto::MsgType::kAck));
    CHECK(decoded<proto::AssocResultT<24>>(r[1]).batch_id == 104);
    CHECK(r[2].type == static_cast<std::uint8_t>(proto::MsgType::kPose));
    CHECK(decoded<proto::Nack>(r[3]).error == proto::Error::kOutOfRange);
  }
  SUBCASE("SUBMAP_ACK with send for the current map closes it now (the end of a run)") {
    h.send(proto::SubmapAck{});  // map 0 taken; map 1 begins
    h.send(test_odometry());
    h.send(test_batch(4));
    h.out.clear();
    proto::SubmapAck close;
    close.map_id = 1;
    close.send = true;
    h.send(close);
    const std::vector<Reply> r = replies(h.out);
    const std::uint32_t f1 = proto::submap_frames(static_cast<std::uint32_t>(s.landmarks()));
    REQUIRE(r.size() == 1 + f1);
    CHECK(r[0].type == static_cast<std::uint8_t>(proto::MsgType::kAck));
    CHECK(static_cast<int>(assemble(r, 1, f1, 1).landmarks.size()) == s.landmarks());
    h.out.clear();
    h.send(test_odometry());
    CHECK(error_of(replies(h.out).at(0)) == proto::Error::kBusy);
  }
}

TEST_CASE(
    "node: SUBMAP_SEED seeds the current map, answered by ASSOC_RESULT; a retransmission or another map's seed "
    "changes nothing") {
  Harness h;
  open_submaps(h, 100);
  for (int k = 0; k < 3; ++k) {
    h.send(test_odometry());
    h.send(test_batch(k));
  }
  const ekf::Slam<float, NodeB>& s = h.node->slam_step().slam();
  const int n = s.landmarks();
  REQUIRE(n >= 1);
  const FeatureId next = s.next_id();
  proto::SubmapSeed m;
  m.batch_id = 1000;
  m.map_id = 0;
  m.count = 3;
  m.items[0] = {1.0f, 8.0f, 0.04f, 0.01f, 0.09f, 12.5f};                           // a new place
  m.items[1] = {s.landmark(0).x(), s.landmark(0).y(), 0.04f, 0.0f, 0.04f, 12.5f};  // where landmark 0 is
  m.items[2] = {-3.0f, -6.0f, 0.25f, 0.0f, 0.25f, 1e30f};                          // another new place
  h.out.clear();
  const std::vector<std::uint8_t> frame = h.frame(m, h.seq++);
  h.send_bytes(frame);
  std::vector<Reply> r = replies(h.out);
  REQUIRE(r.size() == 1);
  const auto a = decoded<proto::AssocResult>(r[0]);
  const std::vector<std::uint8_t> answer = r[0].payload;
  CHECK(a.batch_id == 1000);
  REQUIRE(a.count == 3);
  CHECK(a.pairs[0].outcome == proto::PairingOutcome::kNewLandmark);
  CHECK(a.pairs[0].feature_id == next);
  CHECK(a.pairs[1].outcome == proto::PairingOutcome::kUnmatched);  // the map holds it: the join pairs them
  CHECK(a.pairs[1].feature_id == proto::kFeatureUnmatched);
  CHECK(a.pairs[1].d2 < 1e-3f);
  CHECK(a.pairs[2].outcome == proto::PairingOutcome::kNewLandmark);
  CHECK(a.pairs[2].feature_id == next + 1);
  REQUIRE(s.landmarks() == n + 2);
  // Each seed as given: confirmed, its covariance its own, uncorrelated with the pose and the map.
  const int j = s.index_of(next);
  REQUIRE(j >= 0);
  CHECK(s.confirmed(j));
  CHECK(s.existence(j) == 12.5f);    // the evidence the global map banked for it
  const ekf::LandmarkPolicy policy;  // ... at most the policy's saturation
  CHECK(s.existence(s.index_of(next + 1)) == policy.confirm_nats + policy.reserve_nats);
  CHECK(s.landmark(j).x() == 1.0f);
  CHECK(s.landmark(j).y() == 8.0f);
  const int row = ekf::Layout::landmark(j);
  CHECK(s.cov(row, row) == 0.04f);
  CHECK(s.cov(row, row + 1) == 0.01f);
  CHECK(s.cov(row + 1, row + 1) == 0.09f);
  for (int c = 0; c < row; ++c) CHECK(s.cov(c, row) == 0.0f);
  // Sent again (its answer lost): answered again, not seeded twice.
  h.out.clear();
  h.send_bytes(frame);
  r = replies(h.out);
  REQUIRE(r.size() == 1);
  CHECK(r[0].payload == answer);
  CHECK(s.landmarks() == n + 2);
  // Another map's seed: ERROR out of range, nothing seeded.
  m.batch_id = 1001;
  m.map_id = 1;
  h.out.clear();
  h.send(m);
  r = replies(h.out);
  REQUIRE(r.size() == 1);
  CHECK(error_of(r[0]) == proto::Error::kOutOfRange);
  CHECK(s.landmarks() == n + 2);
  // The scans go on with the seeds in the map.
  h.send(test_odometry());
  h.send(test_batch(3));
  CHECK(h.node->stats().scans == 4);
}

TEST_CASE("node: POSE names exactly the landmarks its scan removed") {
  Harness h;
  open_submaps(h, 100);
  h.send(test_odometry());
  h.send(test_batch(0));
  const ekf::Slam<float, NodeB>& s = h.node->slam_step().slam();
  // Seeds all around the robot at the edge of their existence (-3.5 nats, delete at -4): one miss in
  // view removes one.
  proto::SubmapSeed m;
  m.batch_id = 1000;
  m.map_id = 0;
  m.count = 8;
  for (std::size_t k = 0; k < m.count; ++k) {
    const float a = 0.785398f * static_cast<float>(k);
    m.items[k] = {s.pose().x + 3.0f * std::cos(a), s.pose().y + 3.0f * std::sin(a), 0.01f, 0.0f, 0.01f, -3.5f};
  }
  h.send(m);
  std::size_t named = 0;
  for (int k = 1; k < 12; ++k) {
    std::vector<FeatureId> before(static_cast<std::size_t>(s.landmarks()));
    for (int j = 0; j < s.landmarks(); ++j) before[static_cast<std::size_t>(j)] = s.id(j);
    h.out.clear();
    h.send(test_odometry());
    h.send(test_batch(k));
    const std::vector<Reply> r = replies(h.out);
    const auto at = std::find_if(
        r.begin(), r.end(), [](const Reply& q) { return q.type == static_cast<std::uint8_t>(proto::MsgType::kPose); });
    REQUIRE(at != r.end());
    const proto::Pose p = decoded<proto::Pose>(*at);
    std::vector<FeatureId> gone;
    for (FeatureId id : before) {
      if (s.index_of(id) < 0) gone.push_back(id);
    }
    CAPTURE(k);
    CHECK(p.removed == gone.size());
    REQUIRE(p.count == std::min<std::size_t>(gone.size(), proto::kRemovedPerPose));
    for (std::size_t i = 0; i < p.count; ++i) CHECK(p.ids[i].feature_id == gone[i]);
    named += p.count;
  }
  CHECK(named >= 1);  // the scans removed some (the seeds in view, missed)
}
