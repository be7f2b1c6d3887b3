// host_tools/link: the host end of the serial link (docs/protocol.md), and the desktop device.
//   LinkClient     handshake (HELLO -> CAPABILITIES), CONFIG and RESET (acknowledged), ODOMETRY and
//                  OBS_BATCH streams (ASSOC_RESULT + POSE per batch, matched by batch id, waited
//                  for with a timeout; several batches may be in flight), STATS on request and the
//                  device's periodic STATS (last_stats()), PING, SHUTDOWN. A NACK or ERROR reply, a
//                  timeout or a lost reply throws LinkError naming the cause (LinkError::kind).
//                  The stream frames not yet answered are kept, so after a reconnection they can be
//                  sent again with their original seq (the device applies a stream frame once).
//                  A local map handed over (POSE.submap_frames > 0, docs/submaps.md): its SUBMAP and
//                  SUBMAP_COV frames collected (receive_submap, asking again on a timeout), then
//                  SUBMAP_ACK and the stream frames the device refused meanwhile (ERROR busy) sent
//                  again (submap_received).
//   DesktopDevice  the firmware's node::Node in float on a Transport: what geojcbb_device runs and
//                  the tests serve on a pty. The Node (and its state) outlives one transport, so a
//                  port can be closed and another served by the same device.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "geojcbb/core/capacity.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/protocol/protocol.hpp"
#include "geojcbb_host/serial.hpp"

namespace geojcbb::host {

/// The desktop device's capacity: the large firmware configuration's (the controller's observations
/// per scan, a larger map), so the desktop loop and the large Cortex-M4F firmware are the same node.
using DesktopBounds = LargeControllerBounds;
/// Observations per batch on the link: the wire's default batch size, which is the device's.
constexpr std::size_t kLinkMaxObs = proto::kDefaultMaxObsPerBatch;
static_assert(static_cast<std::size_t>(DesktopBounds::kMaxObservations) == kLinkMaxObs, "one batch size on the link");
using LinkObsBatch = proto::ObsBatchT<kLinkMaxObs>;
using LinkAssocResult = proto::AssocResultT<kLinkMaxObs>;

struct LinkError : std::runtime_error {
  enum class Kind {
    kDevice,    ///< NACK or ERROR from the device (a refused request; retrying will not help)
    kNotReady,  ///< ERROR kNotReady: the device has no session (it may have restarted)
    kTimeout,   ///< no reply in time
    kLost,      ///< a later batch's reply came first: this batch's reply is gone for good
    kRestart,   ///< (LinkSession) the device lost the run's state: start the run again
  };
  explicit LinkError(const std::string& what, Kind k = Kind::kDevice) : std::runtime_error(what), kind(k) {}
  Kind kind;
};

class LinkClient {
 public:
  explicit LinkClient(Transport& t, int timeout_ms = 2000) : t_(&t), timeout_ms_(timeout_ms) {}
  /// HELLO until CAPABILITIES (retried `attempts` times, one timeout each). Each HELLO is preceded
  /// by a 0x00, which ends whatever partial frame the device holds.
  proto::Capabilities hello(int attempts = 5);
  /// CONFIG or RESET, then its ACK. Both start a new run: the pending stream frames are dropped.
  void configure(const proto::Config& c);
  void reset(const proto::Reset& r);
  void odometry(const proto::Odometry& o);
  /// ODOM_DELTA, a stream frame instead of ODOMETRY: a pose increment with its covariance.
  void odom_delta(const proto::OdomDelta& d);
  /// RELOCALISE, a stream frame as ODOMETRY: the pose covariance re-set (the relocaliser then takes over).
  void relocalise(const proto::Relocalise& r);
  struct ScanReply {
    LinkAssocResult result;
    proto::Pose pose;
  };
  /// send_scan(b) then receive_scan(b.batch_id).
  ScanReply scan(const LinkObsBatch& b);
  void send_scan(const LinkObsBatch& b);
  /// Waits for the ASSOC_RESULT and POSE of `batch_id`. Replies of earlier batches (duplicates after
  /// a retransmission) are skipped and counted; a later batch's reply first throws kLost.
  ScanReply receive_scan(std::uint32_t batch_id);
  /// SUBMAP_SEED, a stream frame numbered as the batches: global landmarks for the current local map.
  void send_seed(const proto::SubmapSeed& s);
  /// Waits for the ASSOC_RESULT of seed `batch_id` (one pairing per seed: seeded with its id,
  /// compatible with a landmark the map holds, or no room). Earlier replies are skipped as in
  /// receive_scan.
  LinkAssocResult receive_seed(std::uint32_t batch_id);
  /// A local map as it came over the link (docs/submaps.md).
  struct WireSubmap {
    std::uint32_t map_id = 0;
    Pose2<double> pose{};  ///< the robot's last pose in the map's frame
    std::vector<proto::SubmapLandmarkWire> landmarks;
    std::vector<float> cov;  ///< the upper triangle, column by column: (r, c), r <= c, at c (c + 1) / 2 + r
    int frames = 0;          ///< frames of one sending
    int requests = 0;        ///< times the map was asked for again (lost frames, timeouts)
  };
  /// Waits for the frames of map `map_id`; when they have not all come within the timeout, asks for
  /// the map again (SUBMAP_ACK with send), at most `attempts` times, then throws kTimeout.
  WireSubmap receive_submap(std::uint32_t map_id, int attempts = 3);
  /// SUBMAP_ACK with send: the device closes its current map `map_id` now and hands it over (the
  /// end of a run); then receive_submap.
  void request_submap(std::uint32_t map_id);
  /// SUBMAP_ACK: the map arrived; the device starts the next one. Then the stream frames it refused
  /// meanwhile (ERROR busy: batches sent ahead) are sent again, oldest first.
  void submap_received(std::uint32_t map_id);
  /// ERROR busy received: stream frames the device refused during a hand-over (sent again).
  std::uint64_t busy_refusals() const { return busy_; }
  /// STATS_REQUEST, then the next STATS (periodic STATS queued before the request are taken first).
  proto::Stats stats();
  /// The latest STATS received, asked for or periodic (none yet: empty).
  std::optional<proto::Stats> last_stats() const {
    return stats_received_ > 0 ? std::optional<proto::Stats>(latest_stats_) : std::nullopt;
  }
  std::uint64_t stats_received() const { return stats_received_; }
  /// SHUTDOWN with `exit_code`, then its ACK (or the port closing: the device went away).
  void shutdown(std::uint8_t exit_code);
  /// PING with `nonce`, then its PONG.
  void ping(std::uint32_t nonce);
  /// The last CAPABILITIES (a different boot id later means the device restarted).
  const proto::Capabilities& capabilities() const { return caps_; }
  std::uint32_t boot_id() const { return caps_.boot_id; }
  int timeout_ms() const { return timeout_ms_; }

  /// A reopened port: the decoder and the received frames are dropped; seq and the pending stream
  /// frames are kept. NACK/ERROR about frames sent before are ignored from now on (as after CONFIG
  /// and RESET).
  void attach(Transport& t);
  /// Writes the pending stream frames again (same bytes, same seq), oldest first.
  void resend_pending();
  std::size_t pending_frames() const { return pending_.size(); }
  /// Replies skipped because their batch had been answered already.
  std::uint64_t duplicate_replies() const { return duplicates_; }
  /// The host's frame decoder's counters (frames taken, and rejected by cause), over every port
  /// attached: what arrived damaged from the device.
  proto::DecoderCounters frame_counters() const;

 private:
  struct Frame {
    std::uint8_t type;
    std::uint16_t seq;
    std::vector<std::uint8_t> payload;
  };
  enum class Take { kSkip, kTake };
  template <class M>
  void send(const M& m);
  template <class M>
  void send_stream(const M& m, bool is_batch, std::uint32_t batch_id);
  /// Sends m and waits for its ACK; a new run (CONFIG, RESET) drops the pending stream frames.
  template <class M>
  void acknowledged(const M& m, bool new_run);
  /// Reads frames until `accept` takes one (returned); NACK/ERROR throw, STATS are recorded, other
  /// frames the predicate skips are dropped. Throws kTimeout after timeout_ms.
  template <class Accept>
  Frame wait(const char* what, Accept&& accept);
  template <class M>
  M wait_for(const char* what);
  void note_stats(const Frame& f);
  /// Waits for the ASSOC_RESULT (and with_pose the POSE) of batch or seed `batch_id`; then its frames
  /// and the ones before it need no retransmission.
  ScanReply receive_reply(std::uint32_t batch_id, bool with_pose, const std::string& what);
  /// NACK/ERROR about a frame sent before the last CONFIG, RESET or reconnection: ignored.
  bool stale(std::uint16_t seq) const;

  Transport* t_;
  int timeout_ms_;
  std::deque<Frame> queue_;  ///< decoded frames not yet consumed
  struct Pending {
    std::vector<std::uint8_t> bytes;
    bool is_batch;
    std::uint32_t batch_id;
  };
  std::deque<Pending> pending_;  ///< stream frames sent and not yet answered
  proto::Decoder dec_;
  proto::DecoderCounters past_;  ///< the counters of the decoders of ports attached before
  proto::EncodedFrame frame_;
  proto::Capabilities caps_;
  proto::Stats latest_stats_;
  std::uint64_t stats_received_ = 0, duplicates_ = 0, busy_ = 0;
  std::uint16_t seq_ = 0, error_floor_ = 0;
};

/// The firmware's device loop on the desktop: node::Node<float, DesktopBounds> (the large
/// firmware's bounds), or with `default_bounds` the default firmware's (DefaultBounds: 96 landmarks).
class DesktopDevice {
 public:
  explicit DesktopDevice(std::uint32_t boot_id, bool default_bounds = false);
  ~DesktopDevice();
  DesktopDevice(const DesktopDevice&) = delete;
  DesktopDevice& operator=(const DesktopDevice&) = delete;
  /// Serves `t` until `stop` is set, a SHUTDOWN arrives, or the port fails (the exception passes).
  /// Returns the bytes received.
  std::uint64_t serve(Transport& t, const std::atomic<bool>& stop);
  /// A SHUTDOWN was served (its ACK written): the exit code it asked for.
  std::optional<std::uint8_t> shutdown_code() const { return shutdown_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::optional<std::uint8_t> shutdown_;
};

struct ServeResult {
  std::uint64_t bytes = 0;                    ///< received
  std::optional<std::uint8_t> shutdown_code;  ///< set when a SHUTDOWN ended the serving
};
/// Serves a new DesktopDevice on a transport until `stop` is set, a SHUTDOWN arrives or the port
/// closes (the exception passes).
ServeResult serve_device(Transport& t, const std::atomic<bool>& stop, std::uint32_t boot_id,
                         bool default_bounds = false);

}  // namespace geojcbb::host
