#include "geojcbb_host/link.hpp"

#include <chrono>
#include <utility>

#include "geojcbb/node/node.hpp"

namespace geojcbb::host {

namespace {
/// Serial-number order of batch ids (they wrap): true when a is before b.
bool before(std::uint32_t a, std::uint32_t b) { return static_cast<std::int32_t>(a - b) < 0; }
}  // namespace

template <class M>
void LinkClient::send(const M& m) {
  const proto::Error e = proto::encode_message(m, seq_++, 0, frame_);
  if (e != proto::Error::kOk) throw LinkError(std::string("encode: ") + proto::to_string(e));
  t_->write(frame_.bytes.data(), frame_.size);
}

template <class M>
void LinkClient::send_stream(const M& m, bool is_batch, std::uint32_t batch_id) {
  const proto::Error e = proto::encode_message(m, seq_++, 0, frame_);
  if (e != proto::Error::kOk) throw LinkError(std::string("encode: ") + proto::to_string(e));
  // Kept before writing: a write that fails half way is resent whole after a reconnection.
  pending_.push_back(
      Pending{std::vector<std::uint8_t>(frame_.bytes.begin(), frame_.bytes.begin() + frame_.size), is_batch, batch_id});
  t_->write(frame_.bytes.data(), frame_.size);
}

void LinkClient::note_stats(const Frame& f) {
  if (latest_stats_.decode(f.payload.data(), f.payload.size()) == proto::Error::kOk) ++stats_received_;
}

template <class Accept>
LinkClient::Frame LinkClient::wait(const char* what, Accept&& accept) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms_);
  std::uint8_t buf[4096];
  for (;;) {
    while (!queue_.empty()) {  // frames in arrival order
      Frame fr = std::move(queue_.front());
      queue_.pop_front();
      const auto* p = fr.payload.data();
      const std::size_t n = fr.payload.size();
      if (fr.type == static_cast<std::uint8_t>(proto::MsgType::kNack)) {
        proto::Nack k;
        if (k.decode(p, n) == proto::Error::kOk && !stale(k.nacked_seq)) {
          throw LinkError(std::string("NACK of ") + proto::to_string(static_cast<proto::MsgType>(k.nacked_type)) +
                          ": " + proto::to_string(k.error));
        }
      }
      if (fr.type == static_cast<std::uint8_t>(proto::MsgType::kError)) {
        proto::ErrorReport r;
        if (r.decode(p, n) == proto::Error::kOk && r.error == proto::Error::kBusy) {
          ++busy_;  // a stream frame sent during a hand-over: still pending, sent again after SUBMAP_ACK
          continue;
        }
        if (r.decode(p, n) == proto::Error::kOk && !stale(r.offending_seq)) {
          throw LinkError(std::string("ERROR for ") + proto::to_string(static_cast<proto::MsgType>(r.offending_type)) +
                              " seq " + std::to_string(r.offending_seq) + ": " + proto::to_string(r.error),
                          r.error == proto::Error::kNotReady ? LinkError::Kind::kNotReady : LinkError::Kind::kDevice);
        }
      }
      if (fr.type == static_cast<std::uint8_t>(proto::MsgType::kStats)) note_stats(fr);
      if (accept(fr) == Take::kTake) return fr;
      // Anything else (a late reply to an earlier request, a periodic STATS) is skipped.
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) throw LinkError(std::string("timeout waiting for ") + what, LinkError::Kind::kTimeout);
    const std::size_t n = t_->read(buf, sizeof buf, static_cast<int>(left.count()));
    for (std::size_t i = 0; i < n; ++i) {
      proto::FrameView f;
      if (dec_.push(buf[i], f) != proto::Error::kOk) continue;
      queue_.push_back(Frame{f.type, f.seq, std::vector<std::uint8_t>(f.payload, f.payload + f.len)});
    }
  }
}

template <class M>
M LinkClient::wait_for(const char* what) {
  M m;
  wait(what, [&](const Frame& f) {
    return f.type == static_cast<std::uint8_t>(M::kType) &&
                   m.decode(f.payload.data(), f.payload.size()) == proto::Error::kOk
               ? Take::kTake
               : Take::kSkip;
  });
  return m;
}

proto::Capabilities LinkClient::hello(int attempts) {
  for (int a = 0;; ++a) {
    const std::uint8_t flush = 0;
    t_->write(&flush, 1);
    send(proto::Hello{});
    try {
      caps_ = wait_for<proto::Capabilities>("CAPABILITIES");
      return caps_;
    } catch (const LinkError& e) {
      if (e.kind != LinkError::Kind::kTimeout || a + 1 >= attempts) throw;
    }
  }
}

bool LinkClient::stale(std::uint16_t seq) const {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(seq - error_floor_)) < 0;
}

template <class M>
void LinkClient::acknowledged(const M& m, bool new_run) {
  const std::uint16_t seq = seq_;
  if (new_run) {
    pending_.clear();
    error_floor_ = seq;
  }
  send(m);
  const std::string what = std::string("ACK of ") + proto::to_string(M::kType);
  wait(what.c_str(), [&](const Frame& f) {
    proto::Ack a;
    return f.type == static_cast<std::uint8_t>(proto::MsgType::kAck) &&
                   a.decode(f.payload.data(), f.payload.size()) == proto::Error::kOk && a.acked_seq == seq
               ? Take::kTake
               : Take::kSkip;
  });
}

void LinkClient::configure(const proto::Config& c) { acknowledged(c, true); }

void LinkClient::reset(const proto::Reset& r) { acknowledged(r, true); }

void LinkClient::shutdown(std::uint8_t exit_code) {
  proto::Shutdown m;
  m.exit_code = exit_code;
  try {
    acknowledged(m, false);
  } catch (const LinkError&) {
    throw;
  } catch (const std::runtime_error&) {
    // The port closed: the device acted on the SHUTDOWN and went away before its ACK was read (a
    // pseudo-terminal drops what its closed end had not delivered).
  }
}

void LinkClient::ping(std::uint32_t nonce) {
  proto::Ping m;
  m.nonce = nonce;
  send(m);
  wait("PONG", [&](const Frame& f) {
    proto::Pong p;
    return f.type == static_cast<std::uint8_t>(proto::MsgType::kPong) &&
                   p.decode(f.payload.data(), f.payload.size()) == proto::Error::kOk && p.nonce == nonce
               ? Take::kTake
               : Take::kSkip;
  });
}

void LinkClient::odometry(const proto::Odometry& o) { send_stream(o, false, 0); }

void LinkClient::odom_delta(const proto::OdomDelta& d) { send_stream(d, false, 0); }

void LinkClient::relocalise(const proto::Relocalise& r) { send_stream(r, false, 0); }

void LinkClient::send_scan(const LinkObsBatch& b) { send_stream(b, true, b.batch_id); }

LinkClient::ScanReply LinkClient::receive_scan(std::uint32_t batch_id) {
  return receive_reply(batch_id, true, "the reply to batch " + std::to_string(batch_id));
}

void LinkClient::send_seed(const proto::SubmapSeed& s) { send_stream(s, true, s.batch_id); }

LinkAssocResult LinkClient::receive_seed(std::uint32_t batch_id) {
  return receive_reply(batch_id, false, "the answer to seed " + std::to_string(batch_id)).result;
}

LinkClient::ScanReply LinkClient::receive_reply(std::uint32_t batch_id, bool with_pose, const std::string& what) {
  ScanReply r;
  bool have_result = false;
  wait(what.c_str(), [&](const Frame& f) {
    const bool is_result = f.type == static_cast<std::uint8_t>(proto::MsgType::kAssocResult);
    const bool is_pose = f.type == static_cast<std::uint8_t>(proto::MsgType::kPose);
    if (!is_result && !is_pose) return Take::kSkip;
    std::uint32_t id = 0;
    if (is_result) {
      LinkAssocResult m;
      if (m.decode(f.payload.data(), f.payload.size()) != proto::Error::kOk) return Take::kSkip;
      id = m.batch_id;
      if (id == batch_id) r.result = m;
    } else {
      proto::Pose m;
      if (m.decode(f.payload.data(), f.payload.size()) != proto::Error::kOk) return Take::kSkip;
      id = m.batch_id;
      if (id == batch_id) r.pose = m;
    }
    if (before(id, batch_id)) {
      duplicates_ += is_result ? 1 : 0;
      return Take::kSkip;
    }
    if (id != batch_id || (is_pose && (!have_result || !with_pose))) {
      throw LinkError(what + " is lost (" + (is_result ? "ASSOC_RESULT" : "POSE") + " of batch " + std::to_string(id) +
                          " came first)",
                      LinkError::Kind::kLost);
    }
    if (is_result) {
      have_result = true;
      return with_pose ? Take::kSkip : Take::kTake;  // a scan's POSE follows; a seed has none
    }
    return Take::kTake;
  });
  // Answered: its frames and the ones before it need no retransmission.
  while (!pending_.empty()) {
    const bool last = pending_.front().is_batch && pending_.front().batch_id == batch_id;
    pending_.pop_front();
    if (last) break;
  }
  return r;
}

LinkClient::ScanReply LinkClient::scan(const LinkObsBatch& b) {
  send_scan(b);
  return receive_scan(b.batch_id);
}

LinkClient::WireSubmap LinkClient::receive_submap(std::uint32_t map_id, int attempts) {
  WireSubmap w;
  w.map_id = map_id;
  std::vector<bool> have;
  std::size_t got = 0;
  const std::string what = "the frames of local map " + std::to_string(map_id);
  for (int a = 0;; ++a) {
    try {
      wait(what.c_str(), [&](const Frame& f) {
        const bool head = f.type == static_cast<std::uint8_t>(proto::MsgType::kSubmap);
        const bool cov = f.type == static_cast<std::uint8_t>(proto::MsgType::kSubmapCov);
        if (!head && !cov) return Take::kSkip;
        std::uint16_t chunk = 0, chunks = 0;
        if (head) {
          proto::Submap m;
          if (m.decode(f.payload.data(), f.payload.size()) != proto::Error::kOk || m.map_id != map_id)
            return Take::kSkip;
          chunk = m.chunk;
          chunks = m.chunks;
          w.pose = Pose2<double>{m.x_m, m.y_m, m.theta_rad};
          w.landmarks.resize(m.landmarks);
          for (std::size_t k = 0; k < m.count; ++k) w.landmarks[m.first + k] = m.items[k];
          w.cov.resize(proto::submap_cov_entries(m.landmarks));
        } else {
          proto::SubmapCov m;
          if (m.decode(f.payload.data(), f.payload.size()) != proto::Error::kOk || m.map_id != map_id)
            return Take::kSkip;
          chunk = m.chunk;
          chunks = m.chunks;
          if (w.cov.size() < m.offset + m.count) w.cov.resize(m.offset + m.count);
          for (std::size_t k = 0; k < m.count; ++k) w.cov[m.offset + k] = m.items[k].v;
        }
        if (have.size() != chunks) {  // the first frame of a sending
          have.assign(chunks, false);
          got = 0;
        }
        if (!have[chunk]) {
          have[chunk] = true;
          ++got;
        }
        w.frames = chunks;
        return got == have.size() ? Take::kTake : Take::kSkip;
      });
      if (w.cov.size() != proto::submap_cov_entries(static_cast<std::uint32_t>(w.landmarks.size()))) {
        throw LinkError("local map " + std::to_string(map_id) + ": its covariance does not fit its landmarks");
      }
      return w;
    } catch (const LinkError& e) {
      if (e.kind != LinkError::Kind::kTimeout || a + 1 >= attempts) throw;
    }
    ++w.requests;  // frames lost: the device sends the map again from the same memory
    request_submap(map_id);
  }
}

void LinkClient::request_submap(std::uint32_t map_id) {
  proto::SubmapAck m;
  m.map_id = map_id;
  m.send = true;
  acknowledged(m, false);
}

void LinkClient::submap_received(std::uint32_t map_id) {
  proto::SubmapAck m;
  m.map_id = map_id;
  acknowledged(m, false);
  resend_pending();
}

proto::Stats LinkClient::stats() {
  // STATS already received (periodic ones) are older than the answer: record them first.
  for (auto it = queue_.begin(); it != queue_.end();) {
    if (it->type == static_cast<std::uint8_t>(proto::MsgType::kStats)) {
      note_stats(*it);
      it = queue_.erase(it);
    } else {
      ++it;
    }
  }
  send(proto::StatsRequest{});
  return wait_for<proto::Stats>("STATS");
}

proto::DecoderCounters LinkClient::frame_counters() const {
  const proto::DecoderCounters& c = dec_.counters();
  proto::DecoderCounters s;
  s.frames_ok = past_.frames_ok + c.frames_ok;
  s.bad_crc = past_.bad_crc + c.bad_crc;
  s.bad_length = past_.bad_length + c.bad_length;
  s.overrun = past_.overrun + c.overrun;
  s.bad_version = past_.bad_version + c.bad_version;
  s.bad_flags = past_.bad_flags + c.bad_flags;
  return s;
}

void LinkClient::attach(Transport& t) {
  t_ = &t;
  queue_.clear();
  past_ = frame_counters();
  dec_ = proto::Decoder{};
  error_floor_ = seq_;
}

void LinkClient::resend_pending() {
  for (const Pending& p : pending_) t_->write(p.bytes.data(), p.bytes.size());
}

// ---------------------------------------------------------------------------------------------

struct DesktopDevice::Impl {
  std::unique_ptr<node::Node<float, DesktopBounds>> large;
  std::unique_ptr<node::Node<float, DefaultBounds>> small;
  Transport* t = nullptr;
  std::optional<std::uint8_t>* shutdown = nullptr;
  void on_bytes(const std::uint8_t* p, std::size_t n) {
    if (large) {
      large->on_bytes(p, n);
    } else {
      small->on_bytes(p, n);
    }
  }
};

DesktopDevice::DesktopDevice(std::uint32_t boot_id, bool default_bounds) : impl_(std::make_unique<Impl>()) {
  impl_->shutdown = &shutdown_;
  const node::Output out{impl_.get(),
                         [](void* ctx, const std::uint8_t* p, std::size_t n) {
                           Impl* d = static_cast<Impl*>(ctx);
                           if (d->t != nullptr) d->t->write(p, n);
                         },
                         [](void* ctx, std::uint8_t code) { *static_cast<Impl*>(ctx)->shutdown = code; }};
  if (default_bounds) {
    impl_->small = std::make_unique<node::Node<float, DefaultBounds>>();
    impl_->small->start(out, boot_id);
  } else {
    impl_->large = std::make_unique<node::Node<float, DesktopBounds>>();
    impl_->large->start(out, boot_id);
  }
}

DesktopDevice::~DesktopDevice() = default;

std::uint64_t DesktopDevice::serve(Transport& t, const std::atomic<bool>& stop) {
  impl_->t = &t;
  std::uint8_t buf[4096];
  std::uint64_t total = 0;
  try {
    while (!stop.load() && !shutdown_) {
      const std::size_t n = t.read(buf, sizeof buf, 50);
      total += n;
      impl_->on_bytes(buf, n);
    }
  } catch (...) {
    impl_->t = nullptr;
    throw;
  }
  impl_->t = nullptr;
  return total;
}

ServeResult serve_device(Transport& t, const std::atomic<bool>& stop, std::uint32_t boot_id, bool default_bounds) {
  auto d = std::make_unique<DesktopDevice>(boot_id, default_bounds);
  ServeResult r;
  r.bytes = d->serve(t, stop);
  r.shutdown_code = d->shutdown_code();
  return r;
}

}  // namespace geojcbb::host
