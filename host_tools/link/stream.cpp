#include "geojcbb_host/stream.hpp"

#include "geojcbb/ekf/motion.hpp"
#include "geojcbb/node/node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <array>
#include <stdexcept>

#include <strings.h>

namespace geojcbb::host {

void print_score_header(const char* extra) {
  std::printf("  %-8s %6s %8s %7s %6s %6s %10s %8s %8s %10s %10s %9s %s\n", "strategy", "scans", "TP", "TN", "FP", "FN",
              "precision", "recall", "F1", "|x err| m", "|y err| m", "scans/s", extra);
}

void print_score_row(const std::string& name, const RunResult& r, double scans_per_s, const std::string& extra) {
  std::printf("  %-8s %6d %8d %7d %6d %6d %10.4f %8.4f %8.4f %10.4f %10.4f %9.0f %s\n", name.c_str(), r.scans,
              r.score.tp, r.score.tn, r.score.fp, r.score.fn, r.score.precision(), r.score.recall(), r.score.f1(),
              r.mean_abs_x_m, r.mean_abs_y_m, scans_per_s, extra.c_str());
  std::fflush(stdout);
}

std::string describe_stats(const proto::Stats& st) {
  char line[320];
  std::snprintf(line, sizeof line,
                "frames ok %u, bad CRC %u, bad length %u, overrun %u, unknown type %u, invalid field %u, scans %u, "
                "budget hits %u, movers %u",
                st.frames_ok, st.bad_crc, st.bad_length, st.overrun, st.unknown_type, st.invalid_field, st.scans,
                st.budget_hits, st.movers);
  std::string s = line;
  if (st.stack_high_water_bytes > 0) {  // measured by boards that paint their stack (not the desktop device)
    s += ", stack high-water " + std::to_string(st.stack_high_water_bytes) + " bytes";
  }
  return s;
}

proto::Config link_config(const SensorModel& sensor, const RunOptions& o) {
  if (!o.known_map.empty()) {
    throw std::invalid_argument(
        "known_map (--known-map): CONFIG carries no landmarks, so a device would map instead of localise; run it "
        "in process");
  }
  const StepSettings<double> s = step_settings(o, sensor);
  const StepSettings<double> defaults;
  std::string refused;
  for_each_option_pair(s, defaults, [&](const options::Info& info, const auto& v, const auto& d) {
    if (!refused.empty()) return;
    if (!info.range.contains(options::as_double(v))) {
      refused = std::string(info.name) + " is outside its range (docs/options.md)";
    } else if (!node::carried_by_config(options::index_of(info.name)) && !(v == d)) {
      refused = std::string(info.name) + ": CONFIG does not carry it, and it differs from its default";
    }
  });
  if (!refused.empty()) throw std::invalid_argument("cannot run on a device: " + refused);
  if (!(s.max_range_m > s.min_range_m))
    throw std::invalid_argument("cannot run on a device: max_range_m <= min_range_m");
  return node::config_from(s);
}

proto::Config link_config(const Scenario& sc, const RunOptions& o) {
  return link_config(SensorModel{sc.min_range_m, sc.max_range_m, sc.fov_rad, sc.sigma_bearing_rad}, o);
}

void check_capacity(const proto::Config& c, const proto::Capabilities& caps) {
  auto refuse = [](const std::string& what) { throw std::invalid_argument("cannot run on this device: " + what); };
  if (c.groups > caps.max_groups) {
    refuse("groups " + std::to_string(c.groups) + " > the device's " + std::to_string(caps.max_groups));
  }
  if (c.node_budget > caps.max_jcbb_nodes) {
    refuse("node_budget " + std::to_string(c.node_budget) + " > the device's " + std::to_string(caps.max_jcbb_nodes));
  }
  if (c.rjc && c.rjc_subset > caps.max_observations) {
    refuse("rjc_subset " + std::to_string(c.rjc_subset) + " > the device's " + std::to_string(caps.max_observations));
  }
}

// A 3x3 covariance as the wire's upper triangle (c00, c01, c02, c11, c12, c22), in float.
static std::array<float, 6> upper_of(const Eigen::Matrix3d& P) {
  return {static_cast<float>(P(0, 0)), static_cast<float>(P(0, 1)), static_cast<float>(P(0, 2)),
          static_cast<float>(P(1, 1)), static_cast<float>(P(1, 2)), static_cast<float>(P(2, 2))};
}

proto::Reset link_reset(const Pose2<double>& x0, const Eigen::Matrix3d& P0) {
  Eigen::Matrix3d P = P0;
  for (int k = 0; k < 3; ++k) P(k, k) = std::max(P(k, k), 1e-6);
  proto::Reset r;
  r.x_m = static_cast<float>(x0.x);
  r.y_m = static_cast<float>(x0.y);
  r.theta_rad = static_cast<float>(x0.theta);
  r.cov_upper = upper_of(P);
  return r;
}

proto::Reset link_reset(const Scenario& sc) {
  const SimSource src(sc, 0);
  return link_reset(src.x0, src.P0);
}

proto::Odometry link_odometry(const RunInput& in) {
  if (in.increment) {  // refused, not converted: (v, w) would drop the lateral part and the covariance
    throw std::runtime_error("a pose increment goes as ODOM_DELTA (link_odom_delta), not ODOMETRY");
  }
  proto::Odometry o;
  o.v_mps = static_cast<float>(in.v_mps);
  o.w_radps = static_cast<float>(in.w_radps);
  o.dt_s = static_cast<float>(in.dt_s);
  o.sigma_v_mps = static_cast<float>(in.sigma_v_mps);
  o.sigma_w_radps = static_cast<float>(in.sigma_w_radps);
  return o;
}

proto::OdomDelta link_odom_delta(const RunInput& in) {
  proto::OdomDelta d;
  d.dx_m = static_cast<float>(in.dx_m);
  d.dy_m = static_cast<float>(in.dy_m);
  d.dtheta_rad = static_cast<float>(in.dtheta_rad);
  d.cov_upper = upper_of(in.increment_cov);
  return d;
}

proto::Relocalise link_relocalise(const Eigen::Matrix3d& P) {
  proto::Relocalise m;
  m.cov_upper = upper_of(P);
  return m;
}

proto::Odometry link_odometry(const Scenario& sc, const SimStep& step) {
  return link_odometry(SimSource::prediction(sc, step));
}

LinkObsBatch link_batch(const std::vector<SimObservation>& scan, std::uint32_t batch_id, std::size_t max_obs,
                        std::vector<int>& kept) {
  std::vector<SimObservation> s = scan;
  std::sort(s.begin(), s.end(), [](const auto& a, const auto& b) { return a.z.x() < b.z.x(); });
  if (s.size() > std::min(max_obs, kLinkMaxObs)) s.resize(std::min(max_obs, kLinkMaxObs));
  LinkObsBatch b;
  b.batch_id = batch_id;
  b.count = static_cast<std::uint8_t>(s.size());
  kept.clear();
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Eigen::Matrix2d& R = s[i].R;
    b.obs[i] =
        proto::ObservationWire{static_cast<float>(s[i].z.x()), static_cast<float>(s[i].z.y()),
                               static_cast<float>(R(0, 0)), static_cast<float>(R(0, 1)), static_cast<float>(R(1, 1))};
    kept.push_back(s[i].truth);
  }
  return b;
}

LinkObsBatch link_batch(const std::vector<SimObservation>& scan, std::uint32_t batch_id, std::vector<int>& kept) {
  return link_batch(scan, batch_id, kLinkMaxObs, kept);
}

Submap submap_from_wire(const LinkClient::WireSubmap& w, int index) {
  Submap m;
  m.index = index;
  const int n = static_cast<int>(w.landmarks.size());
  const int d = 3 + 2 * n;
  m.x.resize(d);
  m.x.head<3>() << w.pose.x, w.pose.y, w.pose.theta;
  for (int j = 0; j < n; ++j) {
    const proto::SubmapLandmarkWire& l = w.landmarks[static_cast<std::size_t>(j)];
    m.x.segment<2>(3 + 2 * j) << l.x_m, l.y_m;
    m.ids.push_back(l.id);
    m.confirmed.push_back(l.confirmed);
    m.exist_nats.push_back(l.exist_nats);
    m.carried.push_back(l.carried);
  }
  m.P.resize(d, d);
  for (int c = 0; c < d; ++c) {
    for (int r = 0; r <= c; ++r) {
      const std::size_t k =
          static_cast<std::size_t>(c) * static_cast<std::size_t>(c + 1) / 2 + static_cast<std::size_t>(r);
      m.P(r, c) = m.P(c, r) = w.cov[k];
    }
  }
  return m;
}

namespace {

/// The pose after a prediction input: the filter's mean moves by the motion model alone.
Pose2<double> moved(const Pose2<double>& x, const RunInput& in) {
  if (in.increment) {
    return ekf::compose(x, ekf::PoseIncrement<double>{in.dx_m, in.dy_m, in.dtheta_rad, in.increment_cov});
  }
  return ekf::move(x, ekf::Odometry<double>{in.v_mps, in.w_radps, in.dt_s, in.sigma_v_mps, in.sigma_w_radps});
}

struct InFlight {
  std::vector<RunInput> moves;  ///< the predictions sent before the batch (RunOptions::record_trace)
  LinkObsBatch batch;
  std::vector<int> truth;  ///< of the batch's observations, in batch order
  std::chrono::steady_clock::time_point sent;
  double t_s;
  bool have_truth;
  Pose2<double> true_pose;
};

/// One attempt at a run (stream_once): the device configured and reset, the inputs sent, each scan's
/// batch sent and its reply scored (up to `window` batches in flight), and with a submap rule the
/// device's local maps joined on the host into a global map (and, with submap_seed, the local map
/// seeded from it before each batch).
class StreamedRun {
 public:
  StreamedRun(ScanLink& link, RunSource& src, const RunOptions& o, const StreamOptions& so)
      : link_(link),
        o_(o),
        so_(so),
        caps_(link.capabilities()),
        device_obs_(std::min<std::size_t>(kLinkMaxObs, caps_.max_observations)),
        max_obs_(so.max_observations > 0 ? std::min(device_obs_, static_cast<std::size_t>(so.max_observations))
                                         : device_obs_),
        scorer_(src.true_landmarks, o.landmark_group),
        res_(scorer_.result()),
        window_(static_cast<std::size_t>(std::max(1, so.window))),
        last_pose_(src.x0),
        local_last_(src.x0),
        here_(src.x0.x, src.x0.y) {
    const proto::Config c = link_config(src.sensor, o);
    check_capacity(c, caps_);
    link.configure(c);
    link.reset(link_reset(src.x0, src.P0));
    // Sequential map joining: the device's local maps joined on the host (its CONFIG has the rule).
    ss_ = step_settings(o, src.sensor);
    const bool maps = ss_.submap_landmarks > 0 || ss_.submap_distance_m > 0 || ss_.submap_scans > 0;
    global_ = maps ? make_global_map(o, ss_) : nullptr;
    if (o.submap_seed && (!global_ || window_ != 1)) {
      throw std::invalid_argument("submap_seed (--submap-seed) needs a submap rule and a window of 1 batch");
    }
  }

  /// One input: a relocalisation or a prediction sent as it is, a scan sent as a batch (after its
  /// seed) and the oldest batch completed when the window is full.
  void input(RunInput& in) {
    if (in.relocalise) {
      link_.relocalise(link_relocalise(in.pose_cov));
      return;
    }
    if (!in.scan) {
      if (in.increment) {
        link_.odom_delta(link_odom_delta(in));
      } else {
        link_.odometry(link_odometry(in));
      }
      if (o_.record_trace) moves_.push_back(in);
      return;
    }
    send_scan(in);
    if (flight_.size() >= window_) complete();
  }

  /// The batches still in flight completed, the last local map joined, the result scored.
  RunResult finish() {
    while (!flight_.empty()) complete();
    if (o_.record_trace) trace_moves(moves_);
    if (global_) {  // the last local map, closed at the end of the inputs, joined too
      link_.request_submap(map_id_);
      hand_over();
    }
    if (not_augmented_ > 0 && so_.note) {
      so_.note(std::to_string(not_augmented_) + " observations were not added to the map: the device's map is full (" +
               std::to_string(caps_.max_landmarks) + " landmarks)");
    }
    if (!global_) return scorer_.finish();
    RunResult out = scorer_.finish();
    take_global_map(out, *global_, id_truth_);
    smooth_trace(*global_, local_trace_, out.trace);
    return out;
  }

 private:
  /// The pose after each prediction, into the trace.
  void trace_moves(const std::vector<RunInput>& ins) {
    for (const RunInput& in : ins) {
      last_pose_ = moved(last_pose_, in);
      res_.trace.push_back({in.increment ? in.t_s : in.t_s + in.dt_s, last_pose_});
      local_last_ = moved(local_last_, in);
      if (global_) local_trace_.emplace_back(global_->maps(), local_last_);
    }
  }

  /// The device's local map received and joined into the global map.
  void hand_over() {
    const auto t0 = std::chrono::steady_clock::now();
    const LinkClient::WireSubmap w = link_.receive_submap(map_id_);
    const Submap m = submap_from_wire(w, static_cast<int>(map_id_));
    for (FeatureId id : m.ids) {
      const auto k = static_cast<std::size_t>(id);
      if (k >= id_truth_.size()) id_truth_.resize(k + 1, RunScorer::kUnknown);
      id_truth_[k] = scorer_.truth_of(id);
    }
    // The step's cost is not timed through a link (round trips are not steps): the device reports
    // its instruction counts in STATS (geojcbb_qemu --budget gives each local map's largest step).
    record_join(res_.submaps, global_->join(m), *global_, last_t_, id_truth_, o_.landmark_group, 0.0);
    res_.submaps.frames += w.frames;
    res_.submaps.requests += w.requests;
    link_.submap_received(map_id_++);
    held_ = global_->carried_ids();  // the next map begins with the carried ones
    held_known_ = true;
    res_.submaps.handover_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }

  /// The seed of the current local map before a batch: the global map's offer, the device's answer.
  void seed_map() {
    static const std::vector<FeatureId> kNone;
    const Seed seed =
        global_->seed(here_, ss_.local_radius_m, static_cast<int>(proto::kSeedsPerFrame), held_known_ ? held_ : kNone);
    if (seed.first_ids.empty()) return;
    proto::SubmapSeed m;
    m.batch_id = next_batch_++;
    m.map_id = map_id_;
    m.count = static_cast<std::uint8_t>(seed.first_ids.size());
    for (std::size_t k = 0; k < m.count; ++k) {
      const auto q = 2 * static_cast<Eigen::Index>(k);
      m.items[k] = {static_cast<float>(seed.x(q)),
                    static_cast<float>(seed.x(q + 1)),
                    static_cast<float>(seed.P(q, q)),
                    static_cast<float>(seed.P(q, q + 1)),
                    static_cast<float>(seed.P(q + 1, q + 1)),
                    static_cast<float>(seed.exist_nats[k])};
    }
    link_.send_seed(m);
    const LinkAssocResult a = link_.receive_seed(m.batch_id);
    if (a.count != m.count) throw LinkError("the answer to seed " + std::to_string(m.batch_id) + " has another count");
    std::vector<FeatureId> ids(m.count);
    for (std::size_t k = 0; k < m.count; ++k) {
      ids[k] = a.pairs[k].feature_id;
      if (ids[k] < 0) continue;
      held_.push_back(ids[k]);
      const auto first = static_cast<std::size_t>(seed.first_ids[k]);
      scorer_.added(ids[k], first < id_truth_.size() ? id_truth_[first] : RunScorer::kUnknown);
    }
    res_.submaps.seeded +=
        static_cast<int>(std::count_if(ids.begin(), ids.end(), [](FeatureId id) { return id >= 0; }));
    global_->seeded(seed, ids);
  }

  /// A scan's batch (its nearest observations the device takes) sent, after its seed.
  void send_scan(RunInput& in) {
    InFlight f;
    f.batch = link_batch(in.observations, 0, max_obs_, f.truth);  // numbered after its seed
    const int dropped = static_cast<int>(in.observations.size()) - static_cast<int>(f.batch.count);
    if (dropped > 0) {
      res_.dropped_observations += dropped;
      if (!noted_truncation_ && so_.note && device_obs_ < kLinkMaxObs && max_obs_ == device_obs_) {
        so_.note("the device takes at most " + std::to_string(max_obs_) +
                 " observations per scan: the nearest are sent, the rest dropped (counted)");
      }
      noted_truncation_ = true;
    }
    f.t_s = in.t_s;
    f.moves = std::move(moves_);
    moves_.clear();
    f.have_truth = in.have_truth;
    f.true_pose = in.true_pose;
    if (o_.submap_seed) seed_map();
    f.batch.batch_id = next_batch_++;
    f.sent = std::chrono::steady_clock::now();
    link_.send_scan(f.batch);
    flight_.push_back(std::move(f));
  }

  /// The oldest batch's reply: its pairings scored, new landmarks and removals tracked, the pose (in
  /// the world's frame) scored and traced, and a local map the device closed joined.
  void complete() {
    InFlight& f = flight_.front();
    const LinkClient::ScanReply r = link_.receive_scan(f.batch.batch_id);
    res_.association_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - f.sent).count();
    if (r.result.count != f.batch.count || r.result.batch_id != f.batch.batch_id ||
        r.pose.batch_id != f.batch.batch_id) {
      throw LinkError("reply does not match batch " + std::to_string(f.batch.batch_id));
    }
    ++res_.scans;
    paired_.clear();
    for (std::size_t i = 0; i < f.batch.count; ++i) {
      const proto::PairingWire& q = r.result.pairs[i];
      paired_.push_back(q.outcome == proto::PairingOutcome::kPaired ? q.feature_id : -1);
    }
    scorer_.score(f.truth, paired_);
    for (std::size_t i = 0; i < f.batch.count; ++i) {
      const proto::PairingWire& q = r.result.pairs[i];
      if (q.outcome == proto::PairingOutcome::kNewLandmark) {
        scorer_.added(q.feature_id, f.truth[i]);
        held_.push_back(q.feature_id);
      }
      not_augmented_ += q.outcome == proto::PairingOutcome::kNotAugmented;
    }
    const auto& u = r.pose.cov_upper;
    Eigen::Matrix3d P;
    P << u[0], u[1], u[2], u[1], u[3], u[4], u[2], u[4], u[5];
    Pose2<double> x{r.pose.x_m, r.pose.y_m, r.pose.theta_rad};
    const Pose2<double> x_local = x;
    if (global_) global_->to_global(Pose2<double>(x), Eigen::Matrix3d(P), x, P);  // the world's
    here_ = Eigen::Vector2d(x.x, x.y);
    held_known_ = held_known_ && r.pose.removed == r.pose.count;
    for (std::size_t k = 0; k < r.pose.count; ++k) {
      held_.erase(std::remove(held_.begin(), held_.end(), r.pose.ids[k].feature_id), held_.end());
    }
    if (f.have_truth) scorer_.pose(f.t_s, f.true_pose, x, P);
    if (o_.record_trace) {
      trace_moves(f.moves);
      res_.trace.push_back({f.t_s, x});
      if (global_) local_trace_.emplace_back(global_->maps(), x_local);
    }
    local_last_ = x_local;
    last_pose_ = x;
    res_.landmarks = r.pose.landmark_count;
    last_t_ = f.t_s;
    if (r.pose.submap_frames > 0) {  // before the hook, which may ask for STATS
      if (!global_) throw LinkError("the device handed over a local map, but this run has no submap rule");
      hand_over();
      local_last_ = Pose2<double>{0, 0, 0};  // the next map begins here
    }
    if (so_.hook) so_.hook(f.batch, r);
    flight_.pop_front();
  }

  ScanLink& link_;
  const RunOptions& o_;
  const StreamOptions& so_;
  const proto::Capabilities& caps_;
  const std::size_t device_obs_, max_obs_;
  RunScorer scorer_;
  RunResult& res_;
  const std::size_t window_;
  std::deque<InFlight> flight_;
  std::vector<FeatureId> paired_;
  bool noted_truncation_ = false;
  int not_augmented_ = 0;
  std::uint32_t next_batch_ = 0;
  StepSettings<double> ss_;
  std::unique_ptr<GlobalMap> global_;
  std::vector<int> id_truth_;  // landmark id -> its truth
  std::uint32_t map_id_ = 0;
  double last_t_ = 0;            // the last answered scan's time (a join's)
  std::vector<RunInput> moves_;  // predictions since the last batch (for the trace)
  Pose2<double> last_pose_;
  // With local maps: each trace point's local map and its pose there (smooth_trace), the last one.
  std::vector<std::pair<int, Pose2<double>>> local_trace_;
  Pose2<double> local_last_;  // the first map's frame is the world's
  // The seed (SUBMAP_SEED before each batch) around where the robot was at the last reply (the
  // world's frame), less the global landmarks the local map holds (`held`, as in process: the filter's
  // ids). The replies say what it holds: the landmarks carried into it (SUBMAP's flags), the seeds it
  // took and the landmarks it made, less those POSE names removed. A scan that removed more than
  // POSE names leaves it unknown until the next map: then nothing is held back and the device
  // decides (a seed compatible with a landmark it holds is refused, once).
  Eigen::Vector2d here_;
  std::vector<FeatureId> held_;
  bool held_known_ = true;
};

/// One attempt at a run: throws LinkError kRestart when the link asks for a new start.
RunResult stream_once(ScanLink& link, RunSource& src, const RunOptions& o, const StreamOptions& so) {
  StreamedRun run(link, src, o, so);
  RunInput in;
  while (src.next(in)) run.input(in);
  return run.finish();
}

}  // namespace

RunResult stream_run(ScanLink& link, RunSource& src, const RunOptions& o, const StreamOptions& so) {
  link.begin_run();
  for (;;) {
    try {
      return stream_once(link, src, o, so);
    } catch (const LinkError& e) {
      if (e.kind != LinkError::Kind::kRestart) throw;
      src.rewind();  // the session said so (and limits how often)
    }
  }
}

RunResult stream_scenario(LinkClient& link, const Scenario& sc, std::uint64_t seed, const RunOptions& o,
                          const ScanHook& hook) {
  SimSource src(sc, seed, o.max_steps);
  PlainLink pl(link);
  StreamOptions so;
  so.hook = hook;
  return stream_run(pl, src, o, so);
}

}  // namespace geojcbb::host
