// tests/fuzz: libFuzzer target for the device loop (node::Node<float>, the small bounds) as a
// state machine. The input is a program: each op byte picks a frame (HELLO, CONFIG, RESET, ODOMETRY,
// OBS_BATCH, PING, STATS_REQUEST, SHUTDOWN, SUBMAP_ACK, a retransmission, a seq jump, a corrupted or truncated
// frame, a frame with a valid CRC and a poisoned field, garbage), built with the protocol's encoders
// from the following bytes, and fed whole or one byte at a time. After every byte or frame: counters
// never decrease and stay consistent, every reply is a valid frame that decodes (Decoder + dispatch),
// request/reply pairs hold (PING -> PONG with its nonce, HELLO -> one reply), and once a RESET was
// acknowledged the filter's state is finite with the pose covariance and every landmark's 2x2 block
// positive definite. Any violation: __builtin_trap. corpus_runner.cpp runs it over corpus_node/.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <vector>

#include <Eigen/Cholesky>

#include "fuzz_bytes.hpp"
#include "geojcbb/node/node.hpp"
#include "geojcbb/protocol/protocol.hpp"

namespace {

using namespace geojcbb;
// The small controller's capacity, as a type of its own: OptionalStages then compiles the optional
// stages in (SmallControllerBounds' image leaves the window and the hand-over out), so the fuzzer
// reaches them.
using NB = Bounds<16, 24, 4, 2000, 33>;
using Node = node::Node<float, NB>;
constexpr int kMaxObs = NB::kMaxObservations;

using fuzz::require;

/// The fuzzer's bytes (fuzz_bytes.hpp) and this target's numbers from them.
struct Input : fuzz::Bytes {
  using Bytes::Bytes;
  /// Mostly `nominal`, sometimes scaled, sometimes an edge value (NaN, Inf, huge, tiny, denormal).
  float f(float nominal) {
    const std::uint8_t s = u8();
    switch (s & 15) {
      case 0: return std::numeric_limits<float>::quiet_NaN();
      case 1: return s & 16 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
      case 2: return s & 16 ? 3.0e38f : -3.0e38f;
      case 3: return std::numeric_limits<float>::denorm_min() * static_cast<float>(u8());
      case 4: return s & 16 ? 0.0f : -0.0f;
      case 5: return 1e-30f * static_cast<float>(u8());
      case 6: {
        const std::uint32_t bits = u32();
        float v;
        std::memcpy(&v, &bits, sizeof v);
        return v;
      }
      case 7: return -nominal;
      case 8:
      case 9: return nominal * static_cast<float>(u8()) / 64.0f;
      default: return nominal;
    }
  }
};

struct Sink {
  std::vector<std::uint8_t> bytes;
  std::size_t writes = 0, shutdowns = 0;
};

/// Decodes the replies as the host would and checks them.
struct ReplyChecker {
  proto::Decoder dec;
  std::size_t read = 0;
  std::uint16_t next_seq = 0;
  std::uint32_t replies = 0;
  bool reset_acked = false;
  std::uint32_t last_nonce_seen = 0;
  int pongs = 0, capabilities = 0, hello_answers = 0;
  int landmark_count = -1;  ///< of the last POSE

  void consume(const Sink& s) {
    for (; read < s.bytes.size(); ++read) {  // <= bytes written
      proto::FrameView f;
      const proto::Error e = dec.push(s.bytes[read], f);
      if (e == proto::Error::kIncomplete) continue;
      require(e == proto::Error::kOk);  // every reply frames correctly
      require(f.seq == next_seq);       // the device numbers its frames consecutively
      ++next_seq;
      ++replies;
      int visits = 0;
      const proto::Error de = proto::dispatch(f, [&](const auto& m) {
        ++visits;
        on_reply(m);
      });
      require(de == proto::Error::kOk && visits == 1);  // and decodes with valid fields
    }
    require(dec.pending() == 0);  // each write ends on a delimiter
    const proto::DecoderCounters& c = dec.counters();
    require(c.bad_crc == 0 && c.bad_length == 0 && c.overrun == 0 && c.bad_version == 0 && c.bad_flags == 0);
  }
  template <class M>
  void on_reply(const M& m) {
    using proto::MsgType;
    if constexpr (M::kType == MsgType::kAck) {
      if (m.acked_type == static_cast<std::uint8_t>(MsgType::kReset)) reset_acked = true;
    } else if constexpr (M::kType == MsgType::kPong) {
      ++pongs;
      last_nonce_seen = m.nonce;
    } else if constexpr (M::kType == MsgType::kCapabilities) {
      ++capabilities;
      require(m.max_observations == NB::kMaxObservations && m.max_landmarks == NB::kMaxLandmarks &&
              m.scalar_bytes == sizeof(float));
    } else if constexpr (M::kType == MsgType::kAssocResult) {
      require(m.count <= kMaxObs);
    } else if constexpr (M::kType == MsgType::kPose) {
      require(m.landmark_count <= NB::kMaxLandmarks);
      landmark_count = m.landmark_count;
    } else if constexpr (M::kType == MsgType::kSubmap) {  // a hand-over: the map the device holds
      require(m.landmarks <= NB::kMaxLandmarks && m.chunks == proto::submap_frames(m.landmarks));
    } else if constexpr (M::kType == MsgType::kSubmapCov) {
      require(m.offset + m.count <= proto::submap_cov_entries(NB::kMaxLandmarks));
    } else if constexpr (M::kType == MsgType::kHello || M::kType == MsgType::kConfig || M::kType == MsgType::kReset ||
                         M::kType == MsgType::kOdometry || M::kType == MsgType::kObsBatch ||
                         M::kType == MsgType::kPing || M::kType == MsgType::kStatsRequest ||
                         M::kType == MsgType::kShutdown || M::kType == MsgType::kSubmapAck ||
                         M::kType == MsgType::kSubmapSeed) {
      require(false);  // host-to-device types are never sent by the device
    }
  }
};

bool never_decreased(const proto::Stats& a, const proto::Stats& b) {
  return b.frames_ok >= a.frames_ok && b.bad_crc >= a.bad_crc && b.bad_length >= a.bad_length &&
         b.overrun >= a.overrun && b.bad_version >= a.bad_version && b.bad_flags >= a.bad_flags &&
         b.unknown_type >= a.unknown_type && b.invalid_field >= a.invalid_field && b.scans >= a.scans &&
         b.budget_hits >= a.budget_hits;
}

std::uint64_t framing_events(const proto::Stats& s) {
  return std::uint64_t{s.frames_ok} + s.bad_crc + s.bad_length + s.overrun + s.bad_version + s.bad_flags;
}

/// Positive definite, tested on the correlation matrix D^-1/2 P D^-1/2 so that huge or tiny (but
/// finite) entries cannot overflow the test itself.
bool positive_definite(const Eigen::Matrix3d& P) {
  for (int i = 0; i < 3; ++i)
    if (!(P(i, i) > 0)) return false;
  Eigen::Matrix3d Q;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Q(r, c) = P(r, c) / (std::sqrt(P(r, r)) * std::sqrt(P(c, c)));
  return Eigen::LLT<Eigen::Matrix3d>(Q).info() == Eigen::Success;
}

/// The filter's state: finite, the right size, pose covariance and landmark blocks positive definite.
void check_filter(const Node& node) {
  const auto& s = node.slam_step().slam();
  const int n = s.landmarks();
  require(n >= 0 && n <= NB::kMaxLandmarks && s.dim() == 3 + 2 * n);
  for (int i = 0; i < s.dim(); ++i) require(std::isfinite(s.x(i)));
  require(std::fabs(s.x(2)) <= 3.1416f);  // heading wrapped
  for (int r = 0; r < s.dim(); ++r) {
    for (int c = 0; c < s.dim(); ++c) require(std::isfinite(s.cov(r, c)));
  }
  Eigen::Matrix3d Prr;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      Prr(r, c) = s.cov(r, c);
      const double tol = 1e-4 * std::sqrt(double(s.cov(r, r)) * double(s.cov(c, c))) + 1e-30;
      require(std::fabs(double(s.cov(r, c)) - double(s.cov(c, r))) <= tol);
    }
  }
  require(positive_definite(Prr));
  for (int j = 0; j < n; ++j) {  // <= kMaxLandmarks
    const int l = 3 + 2 * j;
    const double a = s.cov(l, l), b = s.cov(l, l + 1), d = s.cov(l + 1, l + 1);
    require(a > 0 && d > 0 && std::fabs(b) < std::sqrt(a) * std::sqrt(d));  // |correlation| < 1, no overflow
  }
}

struct Session {
  Session(Node& n, Sink& k) : node(n), sink(k) {}
  Node& node;
  Sink& sink;
  ReplyChecker rc;
  std::uint16_t seq = 0;
  bool bytewise = false;
  bool clean = true;  ///< the decoder is at a frame boundary (the last byte fed was a delimiter)
  proto::EncodedFrame last;
  std::vector<std::uint8_t> buf;
  std::vector<unsigned char> filter_bytes;  ///< the filter's bytes at its last full check

  void check(const proto::Stats& before) {
    const proto::Stats now = node.stats();
    require(never_decreased(before, now));
    require(now.scans <= now.frames_ok && now.budget_hits <= now.scans);
    rc.consume(sink);
    if (rc.reset_acked) check_filter_if_changed(framing_events(before) != framing_events(now));
    if (rc.landmark_count >= 0) require(rc.landmark_count <= NB::kMaxLandmarks);
  }

  /// The filter changes only when the node processes a frame. After a call that ended a frame (or
  /// the first time) the whole state is checked (check_filter) and its bytes kept; after any other
  /// call the bytes must be exactly those kept. That is the same invariant after every byte, at the
  /// cost of a memcmp instead of a definiteness check per byte.
  void check_filter_if_changed(bool frame_ended) {
    using Slam = std::remove_reference_t<decltype(node.slam_step().slam())>;
    static_assert(std::is_trivially_copyable<Slam>::value, "the filter is compared byte for byte");
    const auto* bytes = reinterpret_cast<const unsigned char*>(&node.slam_step().slam());
    if (frame_ended || filter_bytes.empty()) {
      check_filter(node);
      filter_bytes.assign(bytes, bytes + sizeof(Slam));
    } else {
      require(std::memcmp(filter_bytes.data(), bytes, sizeof(Slam)) == 0);
    }
  }

  /// Feeds bytes whole or one at a time, checking after each call.
  void feed(const std::uint8_t* p, std::size_t n) {
    if (n == 0) return;
    if (bytewise) {
      for (std::size_t i = 0; i < n; ++i) {  // <= n
        const proto::Stats before = node.stats();
        node.on_bytes(p + i, 1);
        const proto::Stats now = node.stats();
        // One byte ends at most one frame: a delimiter, or the byte that overflows the decoder's
        // buffer (an overrun, counted there once; its frame's remaining bytes are discarded up to
        // the next delimiter, docs/protocol.md). Any other byte counts nothing.
        const std::uint64_t events = framing_events(now) - framing_events(before);
        require(events <= 1);
        if (p[i] != proto::kDelimiter) require(events == std::uint64_t{now.overrun} - before.overrun);
        check(before);
      }
    } else {
      const proto::Stats before = node.stats();
      node.on_bytes(p, n);
      check(before);
    }
    clean = p[n - 1] == proto::kDelimiter;
  }

  /// A whole valid frame: the device must take it (frames_ok + 1) and answer at most 3 frames
  /// (ASSOC_RESULT, POSE, STATS) and a local map's hand-over (at most its frames at full capacity);
  /// unknown-type and invalid-field counts come with an ERROR.
  void feed_frame(const proto::EncodedFrame& f) {
    const bool was_clean = clean;
    const proto::Stats before = node.stats();
    const std::uint32_t replies_before = rc.replies;
    feed(f.bytes.data(), f.size);
    const proto::Stats now = node.stats();
    if (was_clean) require(now.frames_ok == before.frames_ok + 1);
    require(rc.replies - replies_before <= 3 + proto::submap_frames(NB::kMaxLandmarks));
    if (now.unknown_type + now.invalid_field > before.unknown_type + before.invalid_field) {
      require(rc.replies > replies_before);
    }
    last = f;
  }

  template <class M>
  void send(const M& m, std::uint8_t fl = 0) {
    proto::EncodedFrame f;
    // The encoder refuses invalid fields (NaN, out of range): nothing is sent, as a host would do.
    // Invalid fields reach the device through send_poisoned.
    if (proto::encode_message(m, seq, fl, f) != proto::Error::kOk) return;
    ++seq;
    feed_frame(f);
  }

  /// A frame with a valid CRC whose payload is M's with 4 bytes overwritten (NaN, Inf, ...): the
  /// device's own validation, not the encoder's, must refuse it.
  template <class M>
  void send_poisoned(const M& m, Input& in) {
    std::array<std::uint8_t, M::kMaxPayloadSize> p{};
    std::size_t n = 0;
    if (m.encode(p.data(), p.size(), n) != proto::Error::kOk || n == 0) return;
    const std::size_t at = in.u8() % n;
    const float v = in.f(0.0f);
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    for (std::size_t k = 0; k < 4 && at + k < n; ++k) p[at + k] = static_cast<std::uint8_t>(bits >> (8 * k));
    const std::size_t len = in.u8() & 1 ? n : in.u8() % (n + 1);  // sometimes truncated
    proto::EncodedFrame f;
    require(proto::encode_frame(static_cast<std::uint8_t>(M::kType), seq++, 0, p.data(), len, f) == proto::Error::kOk);
    feed_frame(f);
  }
};

proto::Config config_from(Input& in) {
  proto::Config c;
  const std::uint8_t which = in.u8();
  c.strategy = static_cast<proto::StrategyCode>(in.u8() % 7);
  c.local_radius_m = 12.0f;
  c.max_range_m = 10.0f;
  if (which & 1) c.confidence = in.f(0.99f);
  if (which & 2) c.new_landmark_level = in.f(0.999f);
  if (which & 4) c.local_radius_m = in.f(12.0f);
  if (which & 8) {
    c.groups = static_cast<std::uint8_t>(in.u8() % 8);
    c.condition_groups = in.u8() & 1;
    c.dbscan_min_points = static_cast<std::uint8_t>(in.u8() % 6);
    c.dbscan_eps_m = in.f(1.5f);
  }
  if (which & 16) c.node_budget = in.u8() & 1 ? in.u32() : in.u16() % 64;
  if (which & 32) {
    c.min_range_m = in.f(0.0f);
    c.max_range_m = in.f(10.0f);
    c.half_fov_rad = in.f(1.5f);
  }
  if (which & 64) {
    c.landmark_confirm_nats = static_cast<float>(in.u8()) * 0.1f;
    c.landmark_delete_nats = -static_cast<float>(in.u8()) * 0.1f;
    c.landmark_reserve_nats = static_cast<float>(in.u8()) * 0.1f;
    c.max_tentative_reviews = in.u8();
  }
  if (which & 128) {
    c.stats_period_scans = static_cast<std::uint16_t>(in.u8() % 4);
    c.submap_scans = in.u8() % 6;  // a local map closed and handed over every few scans
  }
  return c;
}

proto::Reset reset_from(Input& in) {
  proto::Reset r;
  const std::uint8_t which = in.u8();
  r.cov_upper = {0.01f, 0.0f, 0.0f, 0.01f, 0.0f, 0.001f};
  if (which & 1) {
    r.x_m = in.f(1.0f);
    r.y_m = in.f(-1.0f);
    r.theta_rad = in.f(0.5f);
  }
  if (which & 2) {
    for (float& v : r.cov_upper) v = in.f(v == 0.0f ? 0.001f : v);
  }
  return r;
}

proto::Odometry odometry_from(Input& in) {
  proto::Odometry o;
  o.v_mps = 0.5f;
  o.w_radps = 0.1f;
  o.dt_s = 0.1f;
  o.sigma_v_mps = 0.05f;
  o.sigma_w_radps = 0.01f;
  const std::uint8_t which = in.u8();
  if (which & 1) o.v_mps = in.f(0.5f);
  if (which & 2) o.w_radps = in.f(0.1f);
  if (which & 4) o.dt_s = in.f(0.1f);
  if (which & 8) o.sigma_v_mps = in.f(0.05f);
  if (which & 16) o.sigma_w_radps = in.f(0.01f);
  return o;
}

/// A scan: ranges and bearings from the bytes (a few landmarks seen repeatedly), noise mostly nominal.
Node::ObsBatch batch_from(Input& in, std::uint32_t id) {
  Node::ObsBatch b;
  b.batch_id = id;
  const std::uint8_t k = in.u8();
  b.count = static_cast<std::uint8_t>(k % (kMaxObs + 1));
  const bool fuzz_numbers = k & 0x80;
  for (std::size_t i = 0; i < b.count; ++i) {  // <= kMaxObs
    proto::ObservationWire& o = b.obs[i];
    o.range_m = 0.5f + static_cast<float>(in.u8()) / 25.0f;
    o.bearing_rad = (static_cast<float>(in.u8()) - 128.0f) / 41.0f;
    o.r00 = 0.01f;
    o.r01 = 0.0f;
    o.r11 = 3e-4f;
    if (fuzz_numbers) {
      o.range_m = in.f(o.range_m);
      o.bearing_rad = in.f(o.bearing_rad);
      o.r00 = in.f(o.r00);
      o.r01 = in.f(0.001f);
      o.r11 = in.f(o.r11);
    }
  }
  return b;
}

std::unique_ptr<Node> g_node;
std::unique_ptr<Sink> g_sink;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4096) return 0;  // long programs add time, not states
  g_node = std::make_unique<Node>();
  if (!g_sink) g_sink = std::make_unique<Sink>();
  g_sink->bytes.clear();
  g_sink->writes = g_sink->shutdowns = 0;
  g_node->start(node::Output{g_sink.get(),
                             [](void* c, const std::uint8_t* p, std::size_t n) {
                               auto* s = static_cast<Sink*>(c);
                               s->bytes.insert(s->bytes.end(), p, p + n);
                               ++s->writes;
                             },
                             [](void* c, std::uint8_t) { ++static_cast<Sink*>(c)->shutdowns; }},
                0xB007);
  Session s(*g_node, *g_sink);
  Input in(data, size);
  std::uint32_t batch_id = 0;
  for (int ops = 0; in.more() && ops < 256; ++ops) {  // <= 256 ops
    const std::uint8_t op = in.u8();
    s.bytewise = (op & 0x80) != 0;
    switch (op & 15) {
      case 0: {
        proto::Hello h;
        if (op & 0x40) h.schema_hash ^= in.u32();
        if (op & 0x20) h.protocol_version = in.u8();
        const int answers = s.rc.capabilities;
        const std::uint32_t replies = s.rc.replies;
        const bool was_clean = s.clean;
        s.send(h);
        if (was_clean) require(s.rc.replies == replies + 1);  // CAPABILITIES or NACK
        if (was_clean && proto::check_hello(h) == proto::Error::kOk) require(s.rc.capabilities == answers + 1);
        break;
      }
      case 1: s.send(config_from(in), op & 0x40 ? proto::flags::kAckRequested : 0); break;
      case 2: s.send(reset_from(in)); break;
      case 3: s.send(odometry_from(in)); break;
      case 4:
      case 5:
      case 6: s.send(batch_from(in, op & 0x40 ? batch_id : ++batch_id)); break;
      case 7: {
        proto::Ping p;
        p.nonce = in.u32();
        const int pongs = s.rc.pongs;
        const bool was_clean = s.clean;
        s.send(p);
        if (was_clean) require(s.rc.pongs == pongs + 1 && s.rc.last_nonce_seen == p.nonce);
        break;
      }
      case 8: s.send(proto::StatsRequest{}); break;
      case 9: {
        proto::Shutdown sd;
        sd.exit_code = in.u8();
        s.send(sd);
        break;
      }
      case 10: {  // garbage, sometimes ending on a delimiter
        const std::size_t n = in.u8() % 64;
        s.buf.clear();
        for (std::size_t i = 0; i < n; ++i) s.buf.push_back(in.u8());  // <= 63
        if (op & 0x40) s.buf.push_back(proto::kDelimiter);
        s.feed(s.buf.data(), s.buf.size());
        break;
      }
      case 11:  // a retransmission: the last frame again, same seq
        if (s.last.size > 0) s.feed_frame(proto::EncodedFrame(s.last));
        break;
      case 12:  // the host's seq jumps (lost frames, a restart, wrap-around)
        s.seq = op & 0x40 ? static_cast<std::uint16_t>(s.seq - in.u8()) : in.u16();
        break;
      case 13: {  // the last frame corrupted: one bit flipped, or truncated then a delimiter
        if (s.last.size == 0) break;
        s.buf.assign(s.last.bytes.begin(), s.last.bytes.begin() + static_cast<std::ptrdiff_t>(s.last.size));
        const std::size_t at = in.u8() % s.buf.size();
        if (op & 0x40) {
          s.buf[at] = static_cast<std::uint8_t>(s.buf[at] ^ (1u << (in.u8() & 7)));
        } else {
          s.buf.resize(at);
          s.buf.push_back(proto::kDelimiter);
        }
        s.feed(s.buf.data(), s.buf.size());
        break;
      }
      case 14:  // a valid CRC around a poisoned payload
        switch (in.u8() % 4) {
          case 0: s.send_poisoned(odometry_from(in), in); break;
          case 1: s.send_poisoned(reset_from(in), in); break;
          case 2: s.send_poisoned(config_from(in), in); break;
          default: s.send_poisoned(batch_from(in, ++batch_id), in); break;
        }
        break;
      default: {  // SUBMAP_ACK; or a frame of another type (device-to-host or unknown) with a random payload
        if (op & 0x40) {
          proto::SubmapAck a;
          a.map_id = in.u8() % 4;
          a.send = (in.u8() & 1) != 0;
          s.send(a);
          break;
        }
        if (op & 0x20) {  // SUBMAP_SEED: a few landmarks, some bad (not definite)
          proto::SubmapSeed m;
          m.batch_id = ++batch_id;
          m.map_id = in.u8() % 4;
          m.count = static_cast<std::uint8_t>(in.u8() % (proto::kSeedsPerFrame + 1));
          for (std::size_t k = 0; k < m.count; ++k) {
            proto::SeedWire& w = m.items[k];
            w.x_m = static_cast<float>(static_cast<std::int8_t>(in.u8()));
            w.y_m = static_cast<float>(static_cast<std::int8_t>(in.u8()));
            w.p00 = 0.01f * static_cast<float>(in.u8());
            w.p01 = 0.001f * static_cast<float>(static_cast<std::int8_t>(in.u8()));
            w.p11 = 0.01f * static_cast<float>(in.u8());
            w.exist_nats = static_cast<float>(static_cast<std::int8_t>(in.u8()));
          }
          if (m.validate() == proto::Error::kOk) s.send(m);
          break;
        }
        std::array<std::uint8_t, 64> p{};
        const std::size_t n = in.u8() % p.size();
        for (std::size_t i = 0; i < n; ++i) p[i] = in.u8();  // <= 63
        proto::EncodedFrame f;
        require(proto::encode_frame(in.u8(), s.seq++, 0, p.data(), n, f) == proto::Error::kOk);
        s.feed_frame(f);
        break;
      }
    }
  }
  require(g_sink->shutdowns <= g_sink->writes);
  return 0;
}
