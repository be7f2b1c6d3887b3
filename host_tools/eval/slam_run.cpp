#include "geojcbb_host/slam_run.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "geojcbb/node/slam_step.hpp"

namespace geojcbb::host {

namespace {
using EB = Bounds<48, 128, 8, 200000, 400>;  // host evaluation capacity

constexpr int kRemoved = -2;  // feature_truth of a landmark id that has left the map

void check(Status s, const char* what) {
  if (s != Status::kOk) throw std::runtime_error(std::string(what) + ": " + to_string(s));
}
}  // namespace

struct SlamSession::State {
  node::SlamStep<double, EB> step;
  Observations<double, EB> obs;
  Association<double, EB> out;
  node::StepResult<double, EB> result;
  RunOptions opt;
  std::vector<int> feature_truth;   // landmark id -> true landmark it came from (-1 clutter)
  std::vector<int> mapped;          // true landmark -> map landmarks made from it
  std::vector<int> landmark_group;  // true landmark -> its group (empty: each its own)
  int cls(int t) const { return landmark_group.empty() ? t : landmark_group[t]; }
  RunResult res;
};

// The ground-truth association: each observation of a mapped landmark is paired with the candidate
// made from that landmark (the most-seen one when there are duplicates) if its individual d2 passes
// chi2(0.999, 2), which still rejects the data's gross outliers; clutter and landmarks not yet
// mapped stay unpaired (kNewFeature, with d2 to the nearest candidate for the second gate).
static void oracle_associate(SlamSession::State& s, const std::vector<SimObservation>& scan) {
  double gate = 0;
  check(chi2_inv(0.999, 2, gate), "chi2_inv");
  s.out.count = s.obs.count;
  s.out.joint_d2 = 0;
  s.out.diag = AssociationDiagnostics{};
  for (int i = 0; i < s.obs.count; ++i) {
    const int t = scan[static_cast<std::size_t>(i)].truth;
    double best_d2 = std::numeric_limits<double>::infinity(), nearest = best_d2;
    FeatureId best = kNewFeature;
    int best_hits = -1;
    const Prediction<double, EB>& pred = s.step.prediction();
    for (int a = 0; a < pred.count; ++a) {
      const Eigen::Matrix2d S = pred.C.block<2, 2>(2 * a, 2 * a) + s.obs.R[i];
      const Eigen::Vector2d nu = innovation(s.obs.z[i], pred.h[a]);
      const double d2 = nu.dot(S.ldlt().solve(nu));
      nearest = std::min(nearest, d2);
      const FeatureId id = pred.id[a];
      const int hits = s.step.slam().hits(s.step.slam().index_of(id));
      if (t >= 0 && s.feature_truth[id] == t && d2 < gate && hits > best_hits) {
        best = id;
        best_d2 = d2;
        best_hits = hits;
      }
    }
    s.out.feature[i] = best;
    s.out.d2[i] = best == kNewFeature ? nearest : best_d2;
  }
}

SlamSession::SlamSession(const RunOptions& opt, const SensorModel& sensor, std::size_t true_landmarks,
                         const Pose2<double>& x0, const Eigen::Matrix3d& P0)
    : st_(std::make_unique<State>()) {
  State& s = *st_;
  s.opt = opt;
  node::StepSettings<double> ss;
  ss.strategy = opt.strategy;
  ss.params.confidence = opt.confidence;
  ss.params.local_radius_m = sensor.max_range_m + opt.compensation_m;
  ss.params.groups = opt.groups;
  ss.params.condition_groups = opt.condition_groups;
  ss.new_landmark_level = opt.new_landmark_gate;
  ss.view.min_range_m = sensor.min_range_m + opt.view_margin_m;
  ss.view.max_range_m = sensor.max_range_m - opt.view_margin_m;
  ss.view.half_fov_rad = 0.5 * sensor.fov_rad - 3 * sensor.sigma_bearing_rad;
  ss.policy = opt.landmark_policy;
  check(s.step.configure(ss), "configure");
  s.mapped.assign(true_landmarks, 0);
  if (!opt.landmark_group.empty() && opt.landmark_group.size() != true_landmarks) {
    throw std::runtime_error("landmark_group: one entry per true landmark expected");
  }
  s.landmark_group = opt.landmark_group;
  check(s.step.reset(x0, P0), "reset");
}

SlamSession::~SlamSession() = default;

Pose2<double> SlamSession::pose() const { return st_->step.slam().pose(); }

void SlamSession::predict(double v, double w, double dt, double sv, double sw) {
  check(st_->step.predict(ekf::Odometry<double>{v, w, dt, sv, sw}), "predict");
}

void SlamSession::scan(std::vector<SimObservation> scan, const Eigen::Matrix2d& R, double t_s,
                       const Pose2<double>* truth) {
  State& s = *st_;
  RunResult& res = s.res;
  ++res.scans;
  // Observations over the capacity: the nearest are kept.
  std::sort(scan.begin(), scan.end(), [](const auto& a, const auto& b) { return a.z.x() < b.z.x(); });
  if (scan.size() > static_cast<std::size_t>(EB::kMaxObservations)) {
    res.dropped_observations += static_cast<int>(scan.size()) - EB::kMaxObservations;
    scan.resize(EB::kMaxObservations);
  }
  s.obs.clear();
  for (const SimObservation& o : scan) check(s.obs.push(o.z, R), "push");
  ekf::LocalMapStats ls;
  check(s.step.prepare(ls), "predict_local");
  const auto t0 = std::chrono::steady_clock::now();
  if (s.opt.oracle) {
    oracle_associate(s, scan);
  } else {
    check(s.step.associate_prepared(s.obs, s.out), "associate");
  }
  res.association_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  res.budget_hits += s.out.diag.node_budget_hit;
  res.observations += static_cast<int>(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const int t = scan[i].truth;
    const FeatureId f = s.out.feature[i];
    const bool known = t >= 0 && s.mapped[t] > 0;
    if (f >= 0) {
      const int ft = s.feature_truth[f];
      ++((t >= 0 && ft == t) ? res.score.tp : res.score.fp);
      ++((t >= 0 && ft >= 0 && s.cls(ft) == s.cls(t)) ? res.group_score.tp : res.group_score.fp);
    } else if (known) {
      ++res.score.fn;
      ++res.group_score.fn;
    } else {
      ++res.score.tn;
      ++res.group_score.tn;
    }
  }
  // Update, augment and review: the device's code (node::SlamStep).
  check(s.step.commit(s.obs, s.out, s.result), "update");
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const node::Outcome o = s.result.outcome[i];
    if (o == node::Outcome::kNotAugmented) throw std::runtime_error("augment: map capacity exceeded");
    if (o != node::Outcome::kNewLandmark) continue;
    if (static_cast<std::size_t>(s.result.feature[i]) != s.feature_truth.size()) {
      throw std::runtime_error("landmark ids are not handed out in order");
    }
    s.feature_truth.push_back(scan[i].truth);
    if (scan[i].truth >= 0) ++s.mapped[scan[i].truth];
    else ++res.spurious_landmarks;
  }
  if (s.result.review.removed > 0) {
    const ekf::Slam<double, EB>& slam = s.step.slam();
    std::vector<bool> alive(s.feature_truth.size(), false);
    for (int j = 0; j < slam.landmarks(); ++j) alive[slam.id(j)] = true;
    for (std::size_t id = 0; id < s.feature_truth.size(); ++id) {
      if (alive[id] || s.feature_truth[id] == kRemoved) continue;
      if (s.feature_truth[id] >= 0) --s.mapped[s.feature_truth[id]], ++res.removed_true_landmarks;
      else ++res.removed_spurious_landmarks;
      s.feature_truth[id] = kRemoved;
    }
  }
  if (truth == nullptr) return;
  StepRecord r;
  r.t_s = t_s;
  r.truth = *truth;
  const ekf::Slam<double, EB>& slam = s.step.slam();
  r.estimate = slam.pose();
  r.var_x = slam.cov(0, 0);
  r.var_y = slam.cov(1, 1);
  const Eigen::Vector3d e(r.estimate.x - r.truth.x, r.estimate.y - r.truth.y,
                          wrap_angle(r.estimate.theta - r.truth.theta));
  Eigen::Matrix3d P;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) P(a, b) = slam.cov(a, b);
  r.pose_nees = e.dot(P.ldlt().solve(e));
  res.mean_abs_x_m += std::abs(e.x());
  res.mean_abs_y_m += std::abs(e.y());
  res.steps.push_back(r);
}

RunResult SlamSession::finish() {
  State& s = *st_;
  RunResult res = s.res;
  if (!res.steps.empty()) {
    res.mean_abs_x_m /= static_cast<double>(res.steps.size());
    res.mean_abs_y_m /= static_cast<double>(res.steps.size());
  }
  const ekf::Slam<double, EB>& slam = s.step.slam();
  res.landmarks = slam.landmarks();
  for (int j = 0; j < res.landmarks; ++j) {
    const int t = s.feature_truth[slam.id(j)];
    res.map.push_back({slam.landmark(j).x(), slam.landmark(j).y(), t});
    res.spurious_in_map += t < 0;
  }
  return res;
}

RunResult run_slam(const Scenario& sc, std::uint64_t seed, const RunOptions& opt) {
  const Eigen::Vector2d d = sc.waypoints[1] - sc.waypoints[0];
  const Pose2<double> x0{sc.waypoints[0].x(), sc.waypoints[0].y(), std::atan2(d.y(), d.x())};
  const SensorModel sensor{sc.min_range_m, sc.max_range_m, sc.fov_rad, sc.sigma_bearing_rad};
  SlamSession session(opt, sensor, sc.landmarks.size(), x0, Eigen::Matrix3d::Identity() * 1e-12);
  const Eigen::Matrix2d R =
      Eigen::Vector2d(sc.sigma_range_m * sc.sigma_range_m, sc.sigma_bearing_rad * sc.sigma_bearing_rad).asDiagonal();
  Simulator sim(sc, seed);
  SimStep step;
  long k = 0;
  while (sim.step(step) && (opt.max_steps == 0 || k < opt.max_steps)) {
    ++k;
    session.predict(step.v_mps, step.w_radps, sc.dt_s, sc.sigma_v_mps, sc.sigma_w_radps);
    if (step.scan) session.scan(step.observations, R, step.t_s, &step.true_pose);
  }
  return session.finish();
}

}  // namespace geojcbb::host
