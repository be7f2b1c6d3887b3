// host_tools/link: a link session that survives the port closing and the device restarting
// (docs/protocol.md, "Reconnection").
//   - When the transport fails (the port closed) or a reply times out, the session closes the port
//     and reopens it, retrying with a backoff (50 ms doubling to 1 s) until `reconnect_ms` has
//     passed, and says HELLO again.
//   - Same boot id: the device kept its state. The stream frames not yet answered are sent again
//     with their original seq (the device applies a stream frame once and sends the last batch's
//     replies again; replies of batches already scored are skipped, never scored twice), and the
//     interrupted request is retried.
//   - New boot id (the device restarted), or the device says it has no session (ERROR not-ready),
//     or a reply is lost for good: the run's state is gone. The session says so and throws
//     LinkError kRestart, and stream_run starts the run again from its first input (CONFIG, RESET,
//     ...), at most `max_restarts` times per run; one more fails with a LinkError saying why.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "geojcbb_host/stream.hpp"

namespace geojcbb::host {

struct SessionOptions {
  /// Opens the port (e.g. open_transport(path, baud, kind)); called again at every reconnection.
  std::function<std::unique_ptr<Transport>()> open;
  int timeout_ms = 2000;     ///< wait for each reply at most this long
  int reconnect_ms = 10000;  ///< one reconnection (reopen + HELLO) gives up after this long
  int max_restarts = 3;      ///< restarts of one run from its beginning
  /// Notes for the user (reconnections, restarts); default: printed on stdout.
  std::function<void(const std::string&)> note;
};

class LinkSession : public ScanLink {
 public:
  /// Opens the port and says HELLO (retried like a reconnection). Throws LinkError when no device
  /// answers within reconnect_ms.
  explicit LinkSession(SessionOptions o);
  ~LinkSession() override;
  LinkSession(const LinkSession&) = delete;
  LinkSession& operator=(const LinkSession&) = delete;

  void begin_run() override { restarts_in_run_ = 0; }
  void configure(const proto::Config& c) override;
  void reset(const proto::Reset& r) override;
  void odometry(const proto::Odometry& o) override;
  void odom_delta(const proto::OdomDelta& d) override;
  void relocalise(const proto::Relocalise& r) override;
  void send_scan(const LinkObsBatch& b) override;
  LinkClient::ScanReply receive_scan(std::uint32_t batch_id) override;
  void send_seed(const proto::SubmapSeed& s) override;
  LinkAssocResult receive_seed(std::uint32_t batch_id) override;
  LinkClient::WireSubmap receive_submap(std::uint32_t map_id) override;
  void request_submap(std::uint32_t map_id) override;
  void submap_received(std::uint32_t map_id) override;
  const proto::Capabilities& capabilities() const override { return client_->capabilities(); }

  proto::Stats stats();
  void ping(std::uint32_t nonce);
  /// SHUTDOWN: not retried (a device that shut down does not come back).
  void shutdown(std::uint8_t exit_code) { client_->shutdown(exit_code); }
  LinkClient& client() { return *client_; }
  int reconnections() const { return reconnections_; }
  int restarts() const { return restarts_; }  ///< runs started again, over the session

 private:
  /// Runs `op`; on a transport failure, a timeout or a not-ready device, reconnects and, while the
  /// device kept its state, resends the pending frames and retries (at most 3 reconnections). In a
  /// run (`in_run`), a device that lost its state restarts the run (restart()).
  template <class Op>
  auto guarded(const char* what, bool in_run, Op&& op) -> decltype(op());
  /// Closes and opens the port and says HELLO, retrying with the backoff until reconnect_ms; throws
  /// LinkError "`failure` within N ms: <last error>" then (at once for a refused HELLO).
  void connect(const char* failure);
  /// Reopens the port and says HELLO; returns true when the device kept its state (same boot id).
  bool reconnect(const std::string& why);
  /// The run must start again: throws LinkError kRestart, or a fatal LinkError past the limit.
  [[noreturn]] void restart(const std::string& why);
  void say(const std::string& s) const;

  SessionOptions o_;
  std::unique_ptr<Transport> port_;
  std::unique_ptr<LinkClient> client_;
  int reconnections_ = 0, restarts_ = 0, restarts_in_run_ = 0;
};

}  // namespace geojcbb::host
