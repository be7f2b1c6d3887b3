#include "geojcbb_host/link.hpp"

#include <chrono>
#include <utility>

#include "geojcbb/node/node.hpp"

namespace geojcbb::host {

template <class M>
void LinkClient::send(const M& m) {
  const proto::Error e = proto::encode_message(m, seq_++, 0, frame_);
  if (e != proto::Error::kOk) throw LinkError(std::string("encode: ") + proto::to_string(e));
  t_.write(frame_.bytes.data(), frame_.size);
}

template <class M>
M LinkClient::wait(int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  std::uint8_t buf[512];
  for (;;) {
    while (!queue_.empty()) {  // frames in arrival order
      const Frame fr = std::move(queue_.front());
      queue_.pop_front();
      proto::FrameView f;
      f.type = fr.type;
      f.seq = fr.seq;
      f.payload = fr.payload.data();
      f.len = static_cast<std::uint16_t>(fr.payload.size());
      if (f.type == static_cast<std::uint8_t>(proto::MsgType::kNack)) {
        proto::Nack k;
        if (k.decode(f.payload, f.len) == proto::Error::kOk) {
          throw LinkError(std::string("NACK of ") + proto::to_string(static_cast<proto::MsgType>(k.nacked_type)) +
                          ": " + proto::to_string(k.error));
        }
      }
      if (f.type == static_cast<std::uint8_t>(proto::MsgType::kError)) {
        proto::ErrorReport r;
        if (r.decode(f.payload, f.len) == proto::Error::kOk) {
          throw LinkError(std::string("ERROR for ") + proto::to_string(static_cast<proto::MsgType>(r.offending_type)) +
                          " seq " + std::to_string(r.offending_seq) + ": " + proto::to_string(r.error));
        }
      }
      M m;
      if (proto::decode_message(f, m) == proto::Error::kOk) return m;
      // Anything else (a late reply to an earlier request) is skipped.
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) throw LinkError(std::string("timeout waiting for ") + proto::to_string(M::kType));
    const std::size_t n = t_.read(buf, sizeof buf, static_cast<int>(left.count()));
    for (std::size_t i = 0; i < n; ++i) {
      proto::FrameView f;
      if (dec_.push(buf[i], f) != proto::Error::kOk) continue;
      queue_.push_back(Frame{f.type, f.seq, std::vector<std::uint8_t>(f.payload, f.payload + f.len)});
    }
  }
}

proto::Capabilities LinkClient::hello(int attempts) {
  for (int a = 0;; ++a) {
    send(proto::Hello{});
    try {
      const proto::Capabilities c = wait<proto::Capabilities>(timeout_ms_);
      boot_id_ = c.boot_id;
      return c;
    } catch (const LinkError&) {
      if (a + 1 >= attempts) throw;
    }
  }
}

void LinkClient::configure(const proto::Config& c) {
  send(c);
  wait<proto::Ack>(timeout_ms_);
}

void LinkClient::reset(const proto::Reset& r) {
  send(r);
  wait<proto::Ack>(timeout_ms_);
}

void LinkClient::odometry(const proto::Odometry& o) { send(o); }

LinkClient::ScanReply LinkClient::scan(const LinkObsBatch& b) {
  send(b);
  ScanReply r;
  r.result = wait<LinkAssocResult>(timeout_ms_);
  r.pose = wait<proto::Pose>(timeout_ms_);
  return r;
}

proto::Stats LinkClient::stats() {
  send(proto::StatsRequest{});
  return wait<proto::Stats>(timeout_ms_);
}

std::uint64_t serve_device(Transport& t, const std::atomic<bool>& stop, std::uint32_t boot_id) {
  static_assert(DesktopBounds::kMaxObservations == static_cast<int>(kLinkMaxObs), "one batch size on the link");
  auto node = std::make_unique<node::Node<float, DesktopBounds>>();
  node->start(node::Output{&t,
                           [](void* ctx, const std::uint8_t* p, std::size_t n) {
                             static_cast<Transport*>(ctx)->write(p, n);
                           }},
              boot_id);
  std::uint8_t buf[4096];
  std::uint64_t total = 0;
  while (!stop.load()) {
    const std::size_t n = t.read(buf, sizeof buf, 50);
    total += n;
    node->on_bytes(buf, n);
  }
  return total;
}

}  // namespace geojcbb::host
