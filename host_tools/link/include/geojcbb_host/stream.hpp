// host_tools/link: a run's inputs (the simulator's or a MRCLAM log's, geojcbb_host/slam_run.hpp) as
// link messages, and a run of them through a device, scored by the evaluation's RunScorer
// (TP/TN/FP/FN as in docs/evaluation.md, pose error and NEES against the truth).
//   ScanLink     what the streaming needs of a link: LinkClient (one port, no recovery) or
//                LinkSession (reconnects, re-handshakes, resends, restarts runs; session.hpp).
//   stream_run   CONFIG, RESET, then per prediction ODOMETRY and per scan OBS_BATCH; up to
//                `window` batches in flight, replies matched by batch id and scored in order.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "geojcbb_host/global_map.hpp"
#include "geojcbb_host/link.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host {

/// The score table the link programs print (geojcbb_link, geojcbb_qemu): a header, then one row per
/// strategy with TP/TN/FP/FN, precision, recall, F1, mean absolute x/y error and scans/s; `extra`
/// is a last column (its title in the header, its text in a row).
void print_score_header(const char* extra = "");
void print_score_row(const std::string& name, const RunResult& r, double scans_per_s, const std::string& extra = "");
/// A device's STATS as one line: frames and rejections by cause, scans, budget hits, stack.
std::string describe_stats(const proto::Stats& st);

/// CONFIG for a sensor and a run's settings: the step settings SlamSession is configured with
/// (step_settings), as CONFIG carries them (node::config_from: levels and real values as float32).
/// Throws std::invalid_argument before anything is sent, naming the setting, when the run cannot be
/// carried: a known map (CONFIG carries no landmarks), an option CONFIG does not carry set away from
/// its default, or an option outside its range.
proto::Config link_config(const SensorModel& sensor, const RunOptions& o);
proto::Config link_config(const Scenario& sc, const RunOptions& o);
/// Throws std::invalid_argument naming the setting when CONFIG asks more than the device holds
/// (groups, node budget, RJC subset over its capacities): refused, not clamped.
void check_capacity(const proto::Config& c, const proto::Capabilities& caps);
/// RESET at x0 with P0, each diagonal element at least 1e-6 (the float filter's floor).
proto::Reset link_reset(const Pose2<double>& x0, const Eigen::Matrix3d& P0);
proto::Reset link_reset(const Scenario& sc);
proto::Odometry link_odometry(const RunInput& in);
proto::Odometry link_odometry(const Scenario& sc, const SimStep& step);
/// A kidnap's pose covariance as RELOCALISE (float32 on the wire).
proto::Relocalise link_relocalise(const Eigen::Matrix3d& P);
/// A pose increment input (RunInput::increment) as ODOM_DELTA.
proto::OdomDelta link_odom_delta(const RunInput& in);
/// The scan's observations, nearest first, at most max_obs (<= kLinkMaxObs), each with its
/// covariance; `kept` receives their truths.
LinkObsBatch link_batch(const std::vector<SimObservation>& scan, std::uint32_t batch_id, std::size_t max_obs,
                        std::vector<int>& kept);
LinkObsBatch link_batch(const std::vector<SimObservation>& scan, std::uint32_t batch_id, std::vector<int>& kept);

/// What the streaming needs of a link. LinkClient fails on the first fault; LinkSession recovers,
/// and throws LinkError kRestart when the run must start again from its first input.
class ScanLink {
 public:
  virtual ~ScanLink() = default;
  /// A run begins (not called again when it restarts).
  virtual void begin_run() {}
  virtual void configure(const proto::Config& c) = 0;
  virtual void reset(const proto::Reset& r) = 0;
  virtual void odometry(const proto::Odometry& o) = 0;
  /// ODOM_DELTA (a stream frame, instead of ODOMETRY).
  virtual void odom_delta(const proto::OdomDelta& d) = 0;
  /// RELOCALISE (a stream frame, as ODOMETRY).
  virtual void relocalise(const proto::Relocalise& r) = 0;
  virtual void send_scan(const LinkObsBatch& b) = 0;
  virtual LinkClient::ScanReply receive_scan(std::uint32_t batch_id) = 0;
  /// LinkClient::send_seed and receive_seed.
  virtual void send_seed(const proto::SubmapSeed& s) = 0;
  virtual LinkAssocResult receive_seed(std::uint32_t batch_id) = 0;
  /// A local map's hand-over (docs/submaps.md): its frames, asking again when they do not come
  /// (LinkClient::receive_submap); the current map closed at the host's request; the ACK.
  virtual LinkClient::WireSubmap receive_submap(std::uint32_t map_id) = 0;
  virtual void request_submap(std::uint32_t map_id) = 0;
  virtual void submap_received(std::uint32_t map_id) = 0;
  /// The device's CAPABILITIES (capacity, boot id).
  virtual const proto::Capabilities& capabilities() const = 0;
};

/// A LinkClient as a ScanLink (no recovery).
class PlainLink : public ScanLink {
 public:
  explicit PlainLink(LinkClient& c) : c_(c) {}
  void configure(const proto::Config& c) override { c_.configure(c); }
  void reset(const proto::Reset& r) override { c_.reset(r); }
  void odometry(const proto::Odometry& o) override { c_.odometry(o); }
  void odom_delta(const proto::OdomDelta& d) override { c_.odom_delta(d); }
  void relocalise(const proto::Relocalise& r) override { c_.relocalise(r); }
  void send_scan(const LinkObsBatch& b) override { c_.send_scan(b); }
  LinkClient::ScanReply receive_scan(std::uint32_t id) override { return c_.receive_scan(id); }
  void send_seed(const proto::SubmapSeed& s) override { c_.send_seed(s); }
  LinkAssocResult receive_seed(std::uint32_t id) override { return c_.receive_seed(id); }
  LinkClient::WireSubmap receive_submap(std::uint32_t id) override { return c_.receive_submap(id); }
  void request_submap(std::uint32_t id) override { c_.request_submap(id); }
  void submap_received(std::uint32_t id) override { c_.submap_received(id); }
  const proto::Capabilities& capabilities() const override { return c_.capabilities(); }

 private:
  LinkClient& c_;
};

/// What a device answered for one scan, with the batch sent.
using ScanHook = std::function<void(const LinkObsBatch&, const LinkClient::ScanReply&)>;

struct StreamOptions {
  int window = 1;  ///< batches in flight (>= 1); the device's results do not depend on it
  /// At most this many observations per scan (the nearest; 0: as many as the device takes).
  int max_observations = 0;
  /// Called with every scored reply, in batch order (not for replies of a run that restarted).
  ScanHook hook;
  /// Notes for the user (truncated batches); default: none.
  std::function<void(const std::string&)> note;
};

/// A local map from the link as the global map takes it: the state [robot pose, landmarks] and the
/// covariance (from its packed upper triangle), in double.
Submap submap_from_wire(const LinkClient::WireSubmap& w, int index);

/// Streams a run's inputs through a device: CONFIG (strategy and options of `o`), RESET, then
/// ODOMETRY per prediction and OBS_BATCH per scan, each batch truncated to the device's
/// max_observations (nearest first; RunResult::dropped_observations counts the rest). Replies are
/// scored with RunScorer as the in-process run is, except that the device does not report which
/// landmarks left the map (a true landmark counts as mapped once a landmark was made from it) nor
/// its final map. RunResult::association_s sums each batch's time from sending to its reply.
/// With RunOptions::submaps (CONFIG's submap_* rule; the in-process default when none is given),
/// every local map the device hands over is joined into a GlobalMap on the host (as SlamSession
/// does in process), the last one closed at the host's request when the inputs end; poses are
/// scored in the global frame, RunResult::submaps and the map are the global map's. With
/// RunOptions::record_trace, RunResult::trace holds the device's pose after every scan and, between
/// scans, that pose moved by the odometry sent (the filter's mean moves by the same motion model).
/// A LinkError kRestart from the link rewinds the source and starts the run again.
/// Throws LinkError on a link failure, and when a reply does not match its batch.
RunResult stream_run(ScanLink& link, RunSource& src, const RunOptions& o, const StreamOptions& so = {});

/// stream_run over one seed of a simulated scenario (window 1).
RunResult stream_scenario(LinkClient& link, const Scenario& sc, std::uint64_t seed, const RunOptions& o,
                          const ScanHook& hook = nullptr);

}  // namespace geojcbb::host
