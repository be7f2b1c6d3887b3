#include "geojcbb_host/slam_run.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "geojcbb/associate.hpp"
#include "geojcbb/ekf/slam.hpp"

namespace geojcbb::host {

namespace {
using EB = Bounds<48, 128, 8, 200000, 400>;  // host evaluation capacity

struct State {
  ekf::Slam<double, EB> slam;
  ekf::Workspace<double, EB> ekf_ws;
  Observations<double, EB> obs;
  Prediction<double, EB> pred;
  Workspace<double, EB> ws;
  Association<double, EB> out;
};

constexpr int kRemoved = -2;  // feature_truth of a landmark id that has left the map

void check(Status s, const char* what) {
  if (s != Status::kOk) throw std::runtime_error(std::string(what) + ": " + to_string(s));
}
}  // namespace

RunResult run_slam(const Scenario& sc, std::uint64_t seed, const RunOptions& opt) {
  auto st = std::make_unique<State>();
  StrategyParams<double> sp;
  sp.confidence = opt.confidence;
  sp.local_radius_m = sc.max_range_m + opt.compensation_m;
  sp.groups = opt.groups;
  sp.condition_groups = opt.condition_groups;
  AssociationConfig<double, EB> cfg;
  check(make_strategy(opt.strategy, sp, cfg), "make_strategy");
  double second_gate = 0;
  check(chi2_inv(opt.new_landmark_gate, 2, second_gate), "chi2_inv");

  Simulator sim(sc, seed);
  SimStep step;
  RunResult res;
  res.observations = 0;
  std::vector<int> feature_truth;                 // landmark id -> true landmark it came from (-1 clutter)
  std::vector<int> mapped(sc.landmarks.size(), 0);  // true landmark -> map landmarks made from it
  ekf::Visibility<double> view;  // where a mapped landmark is expected: the sensor's view, shrunk
  view.min_range_m = sc.min_range_m + opt.view_margin_m;
  view.max_range_m = sc.max_range_m - opt.view_margin_m;
  view.half_fov_rad = 0.5 * sc.fov_rad - 3 * sc.sigma_bearing_rad;
  {
    const Eigen::Vector2d d = sc.waypoints[1] - sc.waypoints[0];
    const Pose2<double> x0{sc.waypoints[0].x(), sc.waypoints[0].y(), std::atan2(d.y(), d.x())};
    check(st->slam.reset(x0, Mat3<double>::Identity() * 1e-12), "reset");
  }
  const Mat2<double> R = Vec2<double>(sc.sigma_range_m * sc.sigma_range_m,
                                      sc.sigma_bearing_rad * sc.sigma_bearing_rad).asDiagonal();
  std::vector<SimObservation> scan;
  long k = 0;
  while (sim.step(step) && (opt.max_steps == 0 || k < opt.max_steps)) {
    ++k;
    check(st->slam.predict(ekf::Odometry<double>{step.v_mps, step.w_radps, sc.dt_s, sc.sigma_v_mps,
                                                 sc.sigma_w_radps}),
          "predict");
    if (!step.scan) continue;
    ++res.scans;
    // Observations over the capacity: the nearest are kept.
    scan = step.observations;
    std::sort(scan.begin(), scan.end(), [](const auto& a, const auto& b) { return a.z.x() < b.z.x(); });
    if (scan.size() > static_cast<std::size_t>(EB::kMaxObservations)) {
      res.dropped_observations += static_cast<int>(scan.size()) - EB::kMaxObservations;
      scan.resize(EB::kMaxObservations);
    }
    st->obs.clear();
    for (const SimObservation& o : scan) check(st->obs.push(o.z, R), "push");
    ekf::LocalMapStats ls;
    check(st->slam.predict_local(cfg.local_radius_m, st->ekf_ws, st->pred, ls), "predict_local");
    const auto t0 = std::chrono::steady_clock::now();
    check(associate(st->obs, st->pred, cfg, st->ws, st->out), "associate");
    res.association_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    res.budget_hits += st->out.diag.node_budget_hit;
    res.observations += static_cast<int>(scan.size());
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const int t = scan[i].truth;
      const FeatureId f = st->out.feature[i];
      const bool known = t >= 0 && mapped[t] > 0;
      if (f >= 0) {
        ++((t >= 0 && feature_truth[f] == t) ? res.score.tp : res.score.fp);
      } else if (known) {
        ++res.score.fn;
      } else {
        ++res.score.tn;
      }
    }
    check(st->slam.update(st->obs, st->out, st->ekf_ws), "update");
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (st->out.feature[i] != kNewFeature || !(st->out.d2[i] > second_gate)) continue;
      FeatureId id = -1;
      check(st->slam.augment(st->obs.z[i], st->obs.R[i], id), "augment (map capacity)");
      feature_truth.push_back(scan[i].truth);
      if (scan[i].truth >= 0) ++mapped[scan[i].truth];
      else ++res.spurious_landmarks;
    }
    // Landmark bookkeeping: tentative landmarks missed too often leave the map.
    ekf::ReviewStats rs;
    check(st->slam.review(st->pred, st->out, view, opt.landmark_policy, rs), "review");
    if (rs.removed > 0) {
      std::vector<bool> alive(feature_truth.size(), false);
      for (int j = 0; j < st->slam.landmarks(); ++j) alive[st->slam.id(j)] = true;
      for (std::size_t id = 0; id < feature_truth.size(); ++id) {
        if (alive[id] || feature_truth[id] == kRemoved) continue;
        if (feature_truth[id] >= 0) --mapped[feature_truth[id]], ++res.removed_true_landmarks;
        else ++res.removed_spurious_landmarks;
        feature_truth[id] = kRemoved;
      }
    }

    StepRecord r;
    r.t_s = step.t_s;
    r.truth = step.true_pose;
    r.estimate = st->slam.pose();
    r.var_x = st->slam.cov(0, 0);
    r.var_y = st->slam.cov(1, 1);
    const Eigen::Vector3d e(r.estimate.x - r.truth.x, r.estimate.y - r.truth.y,
                            wrap_angle(r.estimate.theta - r.truth.theta));
    Eigen::Matrix3d P;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) P(a, b) = st->slam.cov(a, b);
    r.pose_nees = e.dot(P.ldlt().solve(e));
    res.mean_abs_x_m += std::abs(e.x());
    res.mean_abs_y_m += std::abs(e.y());
    res.steps.push_back(r);
  }
  if (res.scans > 0) {
    res.mean_abs_x_m /= res.scans;
    res.mean_abs_y_m /= res.scans;
  }
  res.landmarks = st->slam.landmarks();
  for (int j = 0; j < res.landmarks; ++j) {
    const int t = feature_truth[st->slam.id(j)];
    res.map.push_back({st->slam.landmark(j).x(), st->slam.landmark(j).y(), t});
    res.spurious_in_map += t < 0;
  }
  return res;
}

}  // namespace geojcbb::host
