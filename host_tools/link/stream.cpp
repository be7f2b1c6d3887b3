#include "geojcbb_host/stream.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace geojcbb::host {

proto::Config link_config(const Scenario& sc, Strategy s, const RunOptions& o) {
  proto::Config c;
  c.strategy = static_cast<proto::StrategyCode>(s);
  c.confidence = static_cast<float>(o.confidence);
  c.new_landmark_level = static_cast<float>(o.new_landmark_gate);
  c.local_radius_m = static_cast<float>(sc.max_range_m + o.compensation_m);
  c.groups = static_cast<std::uint8_t>(o.groups);
  c.condition_groups = o.condition_groups;
  c.node_budget = static_cast<std::uint32_t>(DesktopBounds::kMaxJcbbNodes);
  c.min_range_m = static_cast<float>(sc.min_range_m + o.view_margin_m);
  c.max_range_m = static_cast<float>(sc.max_range_m - o.view_margin_m);
  c.half_fov_rad = static_cast<float>(0.5 * sc.fov_rad - 3 * sc.sigma_bearing_rad);
  c.confirm_hits = static_cast<std::uint8_t>(o.landmark_policy.confirm_hits);
  c.max_misses = static_cast<std::uint8_t>(o.landmark_policy.max_misses);
  c.max_tentative_reviews = static_cast<std::uint8_t>(o.landmark_policy.max_tentative_reviews);
  return c;
}

proto::Reset link_reset(const Scenario& sc) {
  const Eigen::Vector2d d = sc.waypoints[1] - sc.waypoints[0];
  proto::Reset r;
  r.x_m = static_cast<float>(sc.waypoints[0].x());
  r.y_m = static_cast<float>(sc.waypoints[0].y());
  r.theta_rad = static_cast<float>(std::atan2(d.y(), d.x()));
  r.cov_upper = {1e-6f, 0.0f, 0.0f, 1e-6f, 0.0f, 1e-6f};
  return r;
}

proto::Odometry link_odometry(const Scenario& sc, const SimStep& step) {
  proto::Odometry o;
  o.v_mps = static_cast<float>(step.v_mps);
  o.w_radps = static_cast<float>(step.w_radps);
  o.dt_s = static_cast<float>(sc.dt_s);
  o.sigma_v_mps = static_cast<float>(sc.sigma_v_mps);
  o.sigma_w_radps = static_cast<float>(sc.sigma_w_radps);
  return o;
}

LinkObsBatch link_batch(const Scenario& sc, const std::vector<SimObservation>& scan, std::uint32_t batch_id,
                        std::vector<int>& kept) {
  std::vector<SimObservation> s = scan;
  std::sort(s.begin(), s.end(), [](const auto& a, const auto& b) { return a.z.x() < b.z.x(); });
  if (s.size() > kLinkMaxObs) s.resize(kLinkMaxObs);
  LinkObsBatch b;
  b.batch_id = batch_id;
  b.count = static_cast<std::uint8_t>(s.size());
  kept.clear();
  for (std::size_t i = 0; i < s.size(); ++i) {
    b.obs[i] = proto::ObservationWire{static_cast<float>(s[i].z.x()), static_cast<float>(s[i].z.y()),
                                      static_cast<float>(sc.sigma_range_m * sc.sigma_range_m), 0.0f,
                                      static_cast<float>(sc.sigma_bearing_rad * sc.sigma_bearing_rad)};
    kept.push_back(s[i].truth);
  }
  return b;
}

RunResult stream_scenario(LinkClient& link, const Scenario& sc, std::uint64_t seed, Strategy s, const RunOptions& o,
                          const ScanHook& hook) {
  link.configure(link_config(sc, s, o));
  link.reset(link_reset(sc));
  Simulator sim(sc, seed);
  SimStep step;
  RunResult res;
  std::vector<int> feature_truth;                    // landmark id -> true landmark (-1 clutter)
  std::vector<int> mapped(sc.landmarks.size(), 0);   // true landmark -> landmarks made from it (ever)
  std::vector<int> kept;
  std::uint32_t batch = 0;
  long k = 0;
  while (sim.step(step) && (o.max_steps == 0 || k < o.max_steps)) {
    ++k;
    link.odometry(link_odometry(sc, step));
    if (!step.scan) continue;
    const LinkObsBatch b = link_batch(sc, step.observations, batch++, kept);
    const auto t0 = std::chrono::steady_clock::now();
    const LinkClient::ScanReply r = link.scan(b);
    res.association_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r.result.count != b.count || r.result.batch_id != b.batch_id || r.pose.batch_id != b.batch_id) {
      throw LinkError("reply does not match batch " + std::to_string(b.batch_id));
    }
    ++res.scans;
    res.observations += b.count;
    for (std::size_t i = 0; i < b.count; ++i) {
      const int t = kept[i];
      const proto::PairingWire& q = r.result.pairs[i];
      if (q.outcome == proto::PairingOutcome::kPaired) {
        const int ft = static_cast<std::size_t>(q.feature_id) < feature_truth.size() ? feature_truth[q.feature_id] : -3;
        ++((t >= 0 && ft == t) ? res.score.tp : res.score.fp);
      } else if (t >= 0 && mapped[t] > 0) {
        ++res.score.fn;
      } else {
        ++res.score.tn;
      }
      if (q.outcome == proto::PairingOutcome::kNewLandmark) {
        if (static_cast<std::size_t>(q.feature_id) >= feature_truth.size()) feature_truth.resize(q.feature_id + 1, -1);
        feature_truth[q.feature_id] = t;
        if (t >= 0) ++mapped[t];
        else ++res.spurious_landmarks;
      }
    }
    StepRecord sr;
    sr.t_s = step.t_s;
    sr.truth = step.true_pose;
    sr.estimate = Pose2<double>{r.pose.x_m, r.pose.y_m, r.pose.theta_rad};
    sr.var_x = r.pose.cov_upper[0];
    sr.var_y = r.pose.cov_upper[3];
    sr.pose_nees = 0;
    res.mean_abs_x_m += std::abs(sr.estimate.x - sr.truth.x);
    res.mean_abs_y_m += std::abs(sr.estimate.y - sr.truth.y);
    res.steps.push_back(sr);
    res.landmarks = r.pose.landmark_count;
    if (hook) hook(b, r);
  }
  if (!res.steps.empty()) {
    res.mean_abs_x_m /= static_cast<double>(res.steps.size());
    res.mean_abs_y_m /= static_cast<double>(res.steps.size());
  }
  return res;
}

}  // namespace geojcbb::host
