// The device loop in process: a whole session (HELLO, CONFIG, RESET, ODOMETRY, OBS_BATCH, STATS) fed
// as bytes allocates nothing, and every reply is a valid frame of the expected type.
#include <doctest/doctest.h>

#include <memory>
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
