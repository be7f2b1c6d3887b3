// host_tools/link: the host end of the serial link (docs/protocol.md), and the desktop device.
//   LinkClient   handshake (HELLO -> CAPABILITIES), CONFIG and RESET (acknowledged), ODOMETRY and
//                OBS_BATCH streams (ASSOC_RESULT + POSE per batch, waited for with a timeout),
//                STATS. A NACK or ERROR reply throws LinkError naming the code.
//   DesktopNode  the firmware's node::Node in float on a Transport: what geojcbb_device runs and
//                the loopback test serves on a pty.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>
#include <stdexcept>
#include <string>

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/protocol/protocol.hpp"
#include "geojcbb_host/serial.hpp"

namespace geojcbb::host {

/// The desktop device's capacity: the controller's observations per scan, a larger map.
using DesktopBounds = Bounds<24, 64, 5, 20000, 200>;
constexpr std::size_t kLinkMaxObs = 24;
using LinkObsBatch = proto::ObsBatchT<kLinkMaxObs>;
using LinkAssocResult = proto::AssocResultT<kLinkMaxObs>;

struct LinkError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class LinkClient {
 public:
  explicit LinkClient(Transport& t, int timeout_ms = 2000) : t_(t), timeout_ms_(timeout_ms) {}
  /// HELLO until CAPABILITIES (retried `attempts` times, one timeout each).
  proto::Capabilities hello(int attempts = 5);
  void configure(const proto::Config& c);
  void reset(const proto::Reset& r);
  void odometry(const proto::Odometry& o);
  struct ScanReply {
    LinkAssocResult result;
    proto::Pose pose;
  };
  ScanReply scan(const LinkObsBatch& b);
  proto::Stats stats();
  /// The boot id of the last CAPABILITIES (a different one later means the device restarted).
  std::uint32_t boot_id() const { return boot_id_; }

 private:
  template <class M>
  void send(const M& m);
  /// Reads frames until a message of type M arrives; NACK/ERROR throw; other frames are skipped.
  template <class M>
  M wait(int timeout_ms);
  Transport& t_;
  int timeout_ms_;
  struct Frame {
    std::uint8_t type;
    std::uint16_t seq;
    std::vector<std::uint8_t> payload;
  };
  std::deque<Frame> queue_;  ///< decoded frames not yet consumed
  proto::Decoder dec_;
  proto::EncodedFrame frame_;
  std::uint16_t seq_ = 0;
  std::uint32_t boot_id_ = 0;
};

/// Serves node::Node<float, DesktopBounds> on a transport until `stop` is set or the port closes.
/// Returns the number of bytes received.
std::uint64_t serve_device(Transport& t, const std::atomic<bool>& stop, std::uint32_t boot_id);

}  // namespace geojcbb::host
