// host_tools/qemu: MirrorTransport, the bit-for-bit check of a device against the host's float
// pipeline. Every byte the host sends goes to the device and to a node::Node<float, B> in this
// process; every reply the device sends is compared with the in-process node's reply of the same
// type and order: ASSOC_RESULT and POSE (and ACK, NACK, ERROR) payloads byte for byte. CAPABILITIES
// (boot id) and STATS (instruction counts, stack) differ by nature and are not compared.
// Compile this with EIGEN_DONT_VECTORIZE (the Cortex-M4F has no SIMD; Eigen's SSE reductions sum in
// another order), as host_tools/CMakeLists.txt does for geojcbb_qemu.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb/node/node.hpp"
#include "geojcbb_host/serial.hpp"

namespace geojcbb::host {

struct MirrorReport {
  std::uint64_t compared = 0;    ///< replies compared
  std::uint64_t mismatched = 0;  ///< replies that differ (type or payload), or have no counterpart
  std::uint64_t assoc_results = 0, poses = 0;
  std::uint64_t seeds_sent = 0;  ///< SUBMAP_SEED frames the host sent (each answered by an ASSOC_RESULT)
  std::string first_mismatch;    ///< a description of the first one
};

template <class B>
class MirrorTransport : public Transport {
 public:
  /// The device and the in-process node must start together: send the HELLO through this transport.
  explicit MirrorTransport(Transport& device) : dev_(device), ref_(std::make_unique<node::Node<float, B>>()) {
    ref_->start(node::Output{this, &MirrorTransport::on_ref_bytes}, 0);
  }
  std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) override {
    const std::size_t k = dev_.read(p, n, timeout_ms);
    for (std::size_t i = 0; i < k; ++i) {
      proto::FrameView f;
      if (dev_dec_.push(p[i], f) == proto::Error::kOk) compare(f);
    }
    return k;
  }
  void write(const std::uint8_t* p, std::size_t n) override {
    dev_.write(p, n);
    ref_->on_bytes(p, n);
    for (std::size_t i = 0; i < n; ++i) {
      proto::FrameView f;
      if (host_dec_.push(p[i], f) == proto::Error::kOk)
        report_.seeds_sent += f.type == static_cast<std::uint8_t>(proto::MsgType::kSubmapSeed);
    }
  }
  /// Replies the reference made that the device has not (yet) matched count as mismatches here.
  MirrorReport report() const {
    MirrorReport r = report_;
    if (!expected_.empty()) {
      r.mismatched += expected_.size();
      if (r.first_mismatch.empty()) r.first_mismatch = "the device did not answer a reply the reference made";
    }
    return r;
  }

 private:
  struct Reply {
    std::uint8_t type;
    std::vector<std::uint8_t> payload;
  };
  static bool compared_type(std::uint8_t t) {
    return t != static_cast<std::uint8_t>(proto::MsgType::kCapabilities) &&
           t != static_cast<std::uint8_t>(proto::MsgType::kStats) &&
           t != static_cast<std::uint8_t>(proto::MsgType::kPong);
  }
  static void on_ref_bytes(void* self, const std::uint8_t* p, std::size_t n) {
    auto* m = static_cast<MirrorTransport*>(self);
    for (std::size_t i = 0; i < n; ++i) {
      proto::FrameView f;
      if (m->ref_dec_.push(p[i], f) == proto::Error::kOk && compared_type(f.type)) {
        m->expected_.push_back(Reply{f.type, std::vector<std::uint8_t>(f.payload, f.payload + f.len)});
      }
    }
  }
  void compare(const proto::FrameView& f) {
    if (!compared_type(f.type)) return;
    ++report_.compared;
    if (f.type == static_cast<std::uint8_t>(proto::MsgType::kAssocResult)) ++report_.assoc_results;
    if (f.type == static_cast<std::uint8_t>(proto::MsgType::kPose)) ++report_.poses;
    const std::vector<std::uint8_t> got(f.payload, f.payload + f.len);
    if (expected_.empty() || expected_.front().type != f.type || expected_.front().payload != got) {
      ++report_.mismatched;
      if (report_.first_mismatch.empty()) {
        report_.first_mismatch =
            "reply " + std::to_string(report_.compared) + ": device type 0x" + hex(f.type) +
            (expected_.empty() ? ", reference had none"
                               : ", reference type 0x" + hex(expected_.front().type) +
                                     (expected_.front().type == f.type ? " (payload differs)" : ""));
      }
    }
    if (!expected_.empty()) expected_.pop_front();
  }
  static std::string hex(std::uint8_t v) {
    const char* d = "0123456789abcdef";
    return std::string{d[v >> 4], d[v & 15]};
  }

  Transport& dev_;
  std::unique_ptr<node::Node<float, B>> ref_;
  proto::Decoder dev_dec_, ref_dec_, host_dec_;
  std::deque<Reply> expected_;
  MirrorReport report_;
};

}  // namespace geojcbb::host
