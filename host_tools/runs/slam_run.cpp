#include "geojcbb_host/slam_run.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cctype>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/node/slam_step.hpp"

namespace geojcbb::host {

namespace {
using EB = Bounds<kEvalMaxObservations, 128, 8, 200000, kEvalMaxLandmarks>;  // host evaluation capacity

void check(Status s, const char* what) {
  if (s != Status::kOk) throw std::runtime_error(std::string(what) + ": " + to_string(s));
}
}  // namespace

// ---------------------------------------------------------------------------------------------

struct SlamSession::State {
  node::SlamStep<double, EB> step;
  Observations<double, EB> obs;
  node::StepResult<double, EB> result;
  RunOptions opt;
  std::unique_ptr<RunScorer> scorer;
  std::vector<int> truth;         // scratch: the scan's truths
  std::vector<int> mover;         // scratch: the scan's movers (-1: none)
  std::vector<FeatureId> paired;  // scratch: the scan's pairings
  std::vector<FeatureId> added;   // scratch: the landmarks the scan's observations made
  std::vector<double> closest_m;  // landmark id -> the nearest range it was observed at
  void observed(FeatureId id, double range_m) {
    const auto k = static_cast<std::size_t>(id);
    if (k >= closest_m.size()) closest_m.resize(k + 1, std::numeric_limits<double>::infinity());
    closest_m[k] = std::min(closest_m[k], range_m);
  }
  // Sequential map joining (RunOptions::submaps).
  std::unique_ptr<GlobalMap> global;
  std::vector<int> id_truth;  // landmark id -> its truth, kept when its local map is handed over
  double map_worst_s = 0;     // the current local map's slowest step
  double radius_m = 0;        // r + d
  double last_t = 0;          // the last scan's time
  std::vector<std::pair<int, Pose2<double>>> local_trace;  // per trace point: its local map and pose there
  struct LocalStep {
    int map;
    Pose2<double> pose;
    Eigen::Matrix3d P;
  };
  std::vector<LocalStep> local_steps;  // per scored step: its local map, the pose and covariance there
  /// kGraph: the scored steps' estimates again through their maps' origins as solved at the end
  /// (the joined map's smoothed trajectory), with the origins' marginal covariances.
  void smooth_steps(RunResult& res) const;
  /// The pose and its covariance in the world: the local map's, through the global map's base.
  void world_pose(Pose2<double>& x, Eigen::Matrix3d& P) const {
    const ekf::Slam<double, EB>& slam = step.slam();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) P(a, b) = slam.cov(a, b);
    x = slam.pose();
    if (global) global->to_global(slam.pose(), Eigen::Matrix3d(P), x, P);
  }
  /// The local map handed over: joined into the global map, its landmarks gone from the scorer's
  /// map, the step restarted at the robot's pose.
  void hand_over();
  /// The global map's landmarks near the robot that the local map does not hold, seeded into it
  /// (RunOptions::submap_seed): a place mapped before is closed as a loop, not mapped again.
  void seed_region();
};

void SlamSession::State::hand_over() {
  RunScorer& sc = *scorer;
  SubmapStats& st = sc.result().submaps;
  const ekf::Slam<double, EB>& slam = step.slam();
  Submap m = submap_of(slam, st.maps);
  for (int j = 0; j < slam.landmarks(); ++j) m.carried.push_back(step.carried(j));
  id_truth.resize(sc.ids(), RunScorer::kUnknown);
  for (FeatureId id : m.ids) id_truth[static_cast<std::size_t>(id)] = sc.truth_of(id);
  record_join(st, global->join(m), *global, last_t, id_truth, opt.landmark_group, map_worst_s);
  map_worst_s = 0;
  check(step.restart(), "restart");
  for (FeatureId id : m.ids) {  // the landmarks not carried into the next map leave the scorer's map
    if (slam.index_of(id) < 0) sc.handed_over(id);
  }
}

void SlamSession::State::seed_region() {
  RunScorer& sc = *scorer;
  const ekf::Slam<double, EB>& slam = step.slam();
  std::vector<FeatureId> held(static_cast<std::size_t>(slam.landmarks()));
  for (int j = 0; j < slam.landmarks(); ++j) held[static_cast<std::size_t>(j)] = slam.id(j);
  const Eigen::Vector2d here = global->to_global(Eigen::Vector2d(slam.pose().x, slam.pose().y));
  const Seed seed = global->seed(here, radius_m, node::kMaxSeeds, held);
  if (seed.first_ids.empty()) return;
  const int count = static_cast<int>(seed.first_ids.size());
  node::MapSeed<double> in[node::kMaxSeeds];
  node::SeedAnswer<double> out[node::kMaxSeeds];
  for (int k = 0; k < count; ++k) {
    in[k].l = seed.x.segment<2>(2 * k);
    in[k].P = seed.P.block<2, 2>(2 * k, 2 * k);
    in[k].exist_nats = seed.exist_nats[static_cast<std::size_t>(k)];
  }
  check(step.seed(in, count, out), "seed");
  std::vector<FeatureId> ids(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) ids[static_cast<std::size_t>(k)] = out[k].id;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (ids[k] < 0) continue;
    sc.added(ids[k], id_truth[static_cast<std::size_t>(seed.first_ids[k])]);
    ++sc.result().submaps.seeded;
  }
  global->seeded(seed, ids);
}

std::unique_ptr<GlobalMap> make_global_map(const RunOptions& opt, const StepSettings<double>& step) {
  JoinOptions join = opt.join;
  if (!parse_preset(opt.join_preset.c_str(), join.preset)) {
    throw std::invalid_argument("unknown join preset '" + opt.join_preset + "' (" + kPresetsHelp + ")");
  }
  join.confidence = step.confidence;
  return std::make_unique<GlobalMap>(join);
}

void record_join(SubmapStats& st, const JoinResult& joined, const GlobalMap& global, double t_s,
                 const std::vector<int>& id_truth, const std::vector<int>& landmark_group, double worst_step_s) {
  ++st.maps;
  st.offered += joined.offered;
  st.fused += joined.fused;
  st.declined += joined.declined;
  st.removed += joined.removed;
  st.refused += joined.refused;
  auto truth = [&](FeatureId id) {
    const auto k = static_cast<std::size_t>(id);
    return k < id_truth.size() ? id_truth[k] : -1;
  };
  for (const auto& p : joined.pairs) {
    const int a = truth(p.first), b = truth(p.second);
    if (a < 0 || b < 0 || a == b) continue;
    ++st.wrong;
    const auto groups = static_cast<int>(landmark_group.size());
    st.wrong_in_group += a < groups && b < groups &&
                         landmark_group[static_cast<std::size_t>(a)] == landmark_group[static_cast<std::size_t>(b)];
  }
  JoinRecord j;
  static_cast<JoinCounts&>(j) = joined;
  j.t_s = t_s;
  j.worst_step_s = worst_step_s;
  j.global = global.landmarks();
  const Eigen::Matrix3d base_cov = global.base_covariance();
  for (int a = 0; a < 3; ++a) {
    j.base[a] = global.state()(a);
    j.base_sd[a] = std::sqrt(base_cov(a, a));
  }
  st.joins.push_back(j);
}

void take_global_map(RunResult& res, const GlobalMap& global, const std::vector<int>& id_truth) {
  res.landmarks = global.landmarks();
  res.map.clear();
  res.spurious_in_map = 0;
  for (int k = 0; k < res.landmarks; ++k) {
    const auto id = static_cast<std::size_t>(global.first_id(k));
    const int t = id < id_truth.size() ? id_truth[id] : RunScorer::kUnknown;
    res.map.push_back({global.landmark(k).x(), global.landmark(k).y(), t});
    res.spurious_in_map += t < 0;
  }
  res.map_cov = global.landmarks_covariance();
}

// The ground-truth association (the step's association override): each observation of a mapped
// landmark is paired with the candidate made from that landmark (the most-seen one when there are
// duplicates) if its individual d2 passes chi2(0.999, 2), which still rejects the data's gross
// outliers; clutter and landmarks not yet mapped stay unpaired (kNewFeature, with d2 to the nearest
// candidate for the second gate).
struct OracleContext {
  const RunScorer* scorer;
  const std::vector<SimObservation>* scan;
};
static Status oracle_associate(void* ctx, const Observations<double, EB>& obs, const Prediction<double, EB>& pred,
                               const node::MapView<double, EB>& map, Association<double, EB>& out) {
  const auto& c = *static_cast<const OracleContext*>(ctx);
  double gate = 0;
  check(chi2_inv(0.999, 2, gate), "chi2_inv");
  out.count = obs.count;
  out.joint_d2 = 0;
  out.diag = AssociationDiagnostics{};
  for (int i = 0; i < obs.count; ++i) {
    const int t = (*c.scan)[static_cast<std::size_t>(i)].truth;
    double best_d2 = std::numeric_limits<double>::infinity(), nearest = best_d2;
    FeatureId best = kNewFeature;
    int best_hits = -1;
    for (int a = 0; a < pred.count; ++a) {
      const Eigen::Matrix2d S = pred.C.block(a, a) + obs.R[i];
      const Eigen::Vector2d nu = innovation(obs.z[i], pred.h[a]);
      const double d2 = nu.dot(S.ldlt().solve(nu));
      nearest = std::min(nearest, d2);
      const FeatureId id = pred.id[a];
      const int k = map.slot_of(id);  // a candidate is a mapped landmark: k >= 0
      const int hits = k >= 0 ? map.hits(k) : -1;
      if (t >= 0 && c.scorer->truth_of(id) == t && d2 < gate && hits > best_hits) {
        best = id;
        best_d2 = d2;
        best_hits = hits;
      }
    }
    out.feature[i] = best;
    out.d2[i] = best == kNewFeature ? nearest : best_d2;
  }
  return Status::kOk;
}

// The evaluation's clock for StageCounts: nanoseconds of the steady clock, modulo 2^32 (a stage
// takes well under 4 s, so differences are exact).
static std::uint32_t steady_ns() {
  return static_cast<std::uint32_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

std::vector<Method> select_methods(const std::vector<std::string>& names, bool all_presets, bool oracle) {
  std::vector<Method> out;
  if (names.empty()) {
    for (int k = 0; k < (all_presets ? kStrategyCount : kPaperStrategyCount); ++k) {
      out.push_back({static_cast<Strategy>(k), false, false});
    }
    if (all_presets) out.push_back({Strategy::kPcjcbb, false, true, true, true});  // kRobustPreset
  }
  for (const std::string& n : names) {
    Preset p;
    if (!parse_preset(n.c_str(), p)) {
      throw std::invalid_argument("unknown strategy '" + n + "' (" + kPresetsHelp + ")");
    }
    const Method m = Method::from(p);
    out.push_back(m);
  }
  if (oracle) out.push_back({Strategy::kJcbb, true, false});
  return out;
}

StepSettings<double> step_settings(const RunOptions& opt, const SensorModel& sensor) {
  StepSettings<double> ss = opt.step;
  if (ss.sensor_x_m == 0 && ss.sensor_y_m == 0 && ss.sensor_theta_rad == 0) {  // the options give no mount
    ss.sensor_x_m = sensor.x_m;
    ss.sensor_y_m = sensor.y_m;
    ss.sensor_theta_rad = sensor.theta_rad;
  }
  // r + d around the robot's reference point: the sensor's reach from there is its range plus its
  // offset.
  ss.local_radius_m = sensor.max_range_m + std::hypot(ss.sensor_x_m, ss.sensor_y_m) + opt.compensation_m;
  ss.min_range_m = sensor.min_range_m + opt.view_margin_m;
  ss.max_range_m = sensor.max_range_m - opt.view_margin_m;
  ss.half_fov_rad = 0.5 * sensor.fov_rad - 3 * sensor.sigma_bearing_rad;
  if (opt.submaps && ss.submap_landmarks == 0 && ss.submap_distance_m == 0 && ss.submap_scans == 0) {
    ss.submap_landmarks = kDefaultSubmapLandmarks;
  }
  if (!opt.known_map.empty()) {  // a fixed map: nothing added, nothing removed (known landmarks are confirmed
                                 // and the evidence never removes them, ekf::LandmarkPolicy)
    ss.augment = false;
    ss.static_gate_level = StepSettings<double>{}.static_gate_level;
  }
  return ss;
}

SlamSession::SlamSession(const RunOptions& opt, const SensorModel& sensor, std::size_t true_landmarks,
                         const Pose2<double>& x0, const Eigen::Matrix3d& P0)
    : st_(std::make_unique<State>()) {
  State& s = *st_;
  s.opt = opt;
  const StepSettings<double> ss = step_settings(opt, sensor);
  check(s.step.configure(ss), "configure");
  s.scorer = std::make_unique<RunScorer>(true_landmarks, opt.landmark_group);
  check(s.step.reset(x0, P0), "reset");
  if (ss.submap_landmarks > 0 || ss.submap_distance_m > 0 || ss.submap_scans > 0) {  // a closing rule: joined
    s.radius_m = ss.local_radius_m;
    s.global = make_global_map(opt, ss);
  }
  const double v = opt.known_map_sigma_m * opt.known_map_sigma_m;
  for (std::size_t k = 0; k < opt.known_map.size(); ++k) {
    FeatureId id = -1;
    // Surveyed (--known-map: the data set's measured positions): the loop check leaves it alone.
    check(s.step.add_known_landmark(opt.known_map[k], Eigen::Matrix2d::Identity() * v, id, true), "add_known_landmark");
    s.scorer->added(id, static_cast<int>(k));
  }
}

SlamSession::~SlamSession() = default;

Pose2<double> SlamSession::pose() const {
  Pose2<double> x;
  Eigen::Matrix3d P;
  st_->world_pose(x, P);
  return x;
}

void SlamSession::predict(double v_mps, double w_radps, double dt_s, double sigma_v_mps, double sigma_w_radps) {
  check(st_->step.predict(ekf::Odometry<double>{v_mps, w_radps, dt_s, sigma_v_mps, sigma_w_radps}), "predict");
}

void SlamSession::predict(double dx_m, double dy_m, double dtheta_rad, const Eigen::Matrix3d& cov) {
  check(st_->step.predict(ekf::PoseIncrement<double>{dx_m, dy_m, dtheta_rad, cov}), "predict (increment)");
}

void SlamSession::relocalise(const Eigen::Matrix3d& P) {
  check(st_->step.relocalise(st_->step.slam().pose(), P), "relocalise");
  st_->step.lost();  // the relocaliser, when on, takes over (as a device does on RELOCALISE)
}

void SlamSession::scan(std::vector<SimObservation> scan, double t_s, const Pose2<double>* truth) {
  State& s = *st_;
  s.last_t = t_s;
  if (s.global && s.opt.submap_seed) s.seed_region();
  RunScorer& sc = *s.scorer;
  RunResult& res = sc.result();
  ++res.scans;
  // Observations over the capacity: the nearest are kept.
  std::sort(scan.begin(), scan.end(), [](const auto& a, const auto& b) { return a.z.x() < b.z.x(); });
  if (scan.size() > static_cast<std::size_t>(EB::kMaxObservations)) {
    res.dropped_observations += static_cast<int>(scan.size()) - EB::kMaxObservations;
    scan.resize(EB::kMaxObservations);
  }
  s.obs.clear();
  for (const SimObservation& o : scan) check(s.obs.push(o.z, o.R), "push");
  // The device's step, with the ground truth's association in its place when asked.
  OracleContext oracle{s.scorer.get(), &scan};
  const node::AssociationOverride<double, EB> by_truth{oracle_associate, &oracle};
  check(s.step.step(s.obs, s.result, steady_ns, s.opt.oracle ? &by_truth : nullptr), "step");
  const node::StepResult<double, EB>& r = s.result;
  s.map_worst_s = std::max(s.map_worst_s, 1e-9 * double(r.counts.step));
  const node::RelocStats& reloc = r.reloc;
  res.loop_commits += r.loop.verdict == reloc::LoopVerdict::kCommitted;
  res.loop_held_scans += r.loop.verdict == reloc::LoopVerdict::kPending;
  res.windows += r.window.verdict == reloc::WindowVerdict::kOpened;
  res.window_commits += r.window.verdict == reloc::WindowVerdict::kCommitted;
  res.regrouped += r.window.regrouped;
  res.window_held_scans += r.window.verdict == reloc::WindowVerdict::kOpened ||
                           r.window.verdict == reloc::WindowVerdict::kHeld ||
                           r.window.verdict == reloc::WindowVerdict::kExpired;
  // The association's time: the relocaliser, the local map, the association and the stages that
  // edit it (not the update).
  const double assoc_s =
      1e-9 * (double(r.counts.relocalise) + double(r.counts.predict_local) + double(r.counts.associate) +
              double(r.counts.loop) + double(r.counts.window) + double(r.counts.lost_test));
  res.association_s += assoc_s;
  res.budget_hits += r.diag.node_budget_hit;
  s.truth.clear();
  s.mover.clear();
  s.paired.clear();
  for (std::size_t i = 0; i < scan.size(); ++i) {
    s.truth.push_back(scan[i].truth);
    s.mover.push_back(scan[i].mover);
    s.paired.push_back(r.outcome[i] == node::Outcome::kPaired ? r.feature[i] : kNewFeature);
  }
  const int tp0 = res.score.tp, fp0 = res.score.fp;
  sc.score(s.truth, s.paired, s.mover);  // before this scan's new landmarks are added
  const int scan_tp = res.score.tp - tp0, scan_fp = res.score.fp - fp0;
  res.relocalisations += reloc.relocalised;
  res.ambiguous_scans += reloc.ambiguous || r.loop.ambiguous;
  s.added.assign(scan.size(), kNewFeature);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const node::Outcome o = s.result.outcome[i];
    // A full map is a state, as on the device: the observation is not added, and counted.
    res.not_augmented += o == node::Outcome::kNotAugmented;
    if (o != node::Outcome::kNewLandmark) continue;
    if (static_cast<std::size_t>(s.result.feature[i]) != sc.ids()) {
      throw std::runtime_error("landmark ids are not handed out in order");
    }
    sc.added(s.result.feature[i], scan[i].truth, scan[i].mover);
    s.added[i] = s.result.feature[i];
  }
  if (s.opt.on_scan) s.opt.on_scan(ScanOutcome{t_s, &scan, &s.paired, &s.added});
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const FeatureId id = s.paired[i] >= 0 ? s.paired[i] : s.added[i];
    if (id >= 0) s.observed(id, scan[i].z.x());
  }
  res.merges += s.result.review.merged;
  res.movers_caught += s.result.review.movers;
  res.evicted += s.result.review.evicted;
  const Prediction<double, EB>& pred = s.step.prediction();
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (r.outcome[i] != node::Outcome::kPaired) continue;
    ++res.nis_pairings;
    res.nis_sum += r.d2[i];
    for (int c = 0; c < pred.count; ++c) {  // the pair's candidate: its innovation, H P H^T and R
      if (pred.id[static_cast<std::size_t>(c)] != r.feature[i]) continue;
      const Eigen::Vector2d nu(s.obs.z[i].x() - pred.h[static_cast<std::size_t>(c)].x(),
                               wrap_angle(s.obs.z[i].y() - pred.h[static_cast<std::size_t>(c)].y()));
      ++res.innovations.n;
      for (int k = 0; k < 2; ++k) {
        const double R = s.obs.R[i](k, k), S = pred.C(2 * c + k, 2 * c + k) + R;
        res.innovations.nis[k] += nu(k) * nu(k) / S;
        res.innovations.r_share[k] += R / S;
      }
      break;
    }
  }
  if (s.result.review.removed > 0 || s.result.review.merged > 0 || s.result.review.evicted > 0) {
    const ekf::Slam<double, EB>& slam = s.step.slam();
    std::vector<bool> alive(sc.ids(), false);
    for (int j = 0; j < slam.landmarks(); ++j) alive[static_cast<std::size_t>(slam.id(j))] = true;
    for (std::size_t id = 0; id < sc.ids(); ++id) {
      if (!alive[id]) sc.removed(static_cast<FeatureId>(id));
    }
  }
  if (truth == nullptr) {
    if (s.global && r.submap_due) s.hand_over();
    return;
  }
  Pose2<double> x;
  Eigen::Matrix3d P;
  s.world_pose(x, P);
  sc.pose(t_s, *truth, x, P);
  if (s.global) {
    Eigen::Matrix3d Pl;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) Pl(a, b) = s.step.slam().cov(a, b);
    s.local_steps.push_back({s.global->maps(), s.step.slam().pose(), Pl});
  }
  res.steps.back().lost = reloc.state == node::Localisation::kLost;
  res.steps.back().declared_found = reloc.found;
  int paired = 0;
  double nis = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (r.outcome[i] != node::Outcome::kPaired) continue;
    ++paired;
    nis += r.d2[i];
  }
  sc.nis(paired, nis);
  res.steps.back().tp = scan_tp;
  res.steps.back().fp = scan_fp;
  res.steps.back().assoc_s = assoc_s;
  if (s.global && r.submap_due) s.hand_over();
}

void SlamSession::State::smooth_steps(RunResult& res) const {
  if (global->graph() == nullptr || local_steps.size() != res.steps.size() || res.steps.empty()) return;
  std::vector<Eigen::Vector3d> o;
  std::vector<Eigen::Matrix3d> Po;
  global->origins(o, Po);
  res.mean_abs_x_m = res.mean_abs_y_m = 0;
  for (std::size_t k = 0; k < res.steps.size(); ++k) {
    StepRecord& r = res.steps[k];
    const LocalStep& l = local_steps[k];
    const auto m = static_cast<std::size_t>(l.map);
    Pose2<double> x;
    Eigen::Matrix3d P;
    compose(o[m], Po[m], l.pose, l.P, x, P);
    const Eigen::Vector3d e = r.set_estimate(x, P);
    res.mean_abs_x_m += std::abs(e.x());
    res.mean_abs_y_m += std::abs(e.y());
  }
  res.mean_abs_x_m /= static_cast<double>(res.steps.size());
  res.mean_abs_y_m /= static_cast<double>(res.steps.size());
}

void ScanRecorder::on_scan(const ScanOutcome& s) {
  Scan sc;
  sc.t_s = s.t_s;
  sc.obs = *s.scan;
  sc.id.resize(sc.obs.size(), kNewFeature);
  for (std::size_t i = 0; i < sc.obs.size(); ++i) {
    const FeatureId p = (*s.paired)[i], a = (*s.added)[i];
    sc.id[i] = p >= 0 ? p : a;
  }
  scans_.push_back(std::move(sc));
}

void SlamSession::trace(double t, std::vector<TracePoint>& trace) {
  State& s = *st_;
  trace.push_back({t, pose()});
  if (s.global) s.local_trace.emplace_back(s.global->maps(), s.step.slam().pose());
}

void SlamSession::smoothed(std::vector<TracePoint>& trace) const {
  const State& s = *st_;
  if (s.global) smooth_trace(*s.global, s.local_trace, trace);
}

void smooth_trace(const GlobalMap& global, const std::vector<std::pair<int, Pose2<double>>>& local,
                  std::vector<TracePoint>& trace) {
  if (global.graph() == nullptr || local.size() != trace.size()) return;
  const Eigen::Matrix3d zero = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d P;
  for (std::size_t k = 0; k < trace.size(); ++k)
    compose(global.origin(local[k].first), zero, local[k].second, zero, trace[k].pose, P);
}

RunResult SlamSession::finish() {
  State& s = *st_;
  if (s.global) {  // the last local map joined too; the map is the global one
    s.hand_over();
    RunResult res = s.scorer->finish();
    take_global_map(res, *s.global, s.id_truth);
    s.smooth_steps(res);
    return res;
  }
  RunResult res = s.scorer->finish();
  const ekf::Slam<double, EB>& slam = s.step.slam();
  res.landmarks = slam.landmarks();
  for (int j = 0; j < res.landmarks; ++j) {
    const int t = s.scorer->truth_of(slam.id(j));
    const auto id = static_cast<std::size_t>(slam.id(j));
    const double closest = id < s.closest_m.size() ? s.closest_m[id] : std::numeric_limits<double>::infinity();
    res.map.push_back({slam.landmark(j).x(), slam.landmark(j).y(), t, closest});
    res.spurious_in_map += t < 0;
  }
  const ekf::DetectionModel<double>& dm = slam.detection();
  if (s.opt.step.learn_detection) {
    for (int b = 0; b < ekf::DetectionModel<double>::kDetectionBins; ++b) res.learned_pd.push_back(dm.pd_bin(b));
    res.pd_bin_m = dm.bin_m();
  }
  if (s.opt.step.learn_clutter) res.clutter_density = dm.density();
  const int n = 2 * res.landmarks;
  res.map_cov.resize(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) res.map_cov(r, c) = slam.cov(3 + r, 3 + c);
  return res;
}

// ---------------------------------------------------------------------------------------------

RunResult run_inputs(RunSource& src, const RunOptions& opt) {
  SlamSession session(opt, src.sensor, src.true_landmarks, src.x0, src.P0);
  std::vector<TracePoint> trace;
  RunInput in;
  while (src.next(in)) {
    double t = in.t_s;
    if (in.relocalise) {
      session.relocalise(in.pose_cov);
    } else if (in.scan) {
      session.scan(in.observations, in.t_s, in.have_truth ? &in.true_pose : nullptr);
    } else if (in.increment) {
      session.predict(in.dx_m, in.dy_m, in.dtheta_rad, in.increment_cov);
    } else {
      session.predict(in.v_mps, in.w_radps, in.dt_s, in.sigma_v_mps, in.sigma_w_radps);
      t += in.dt_s;
    }
    if (opt.record_trace) session.trace(t, trace);
  }
  RunResult r = session.finish();
  session.smoothed(trace);
  r.trace = std::move(trace);
  return r;
}

RunResult run_slam(const Scenario& sc, std::uint64_t seed, const RunOptions& opt) {
  SimSource src(sc, seed, opt.max_steps);
  return run_inputs(src, opt);
}

RunResult innovation_round(const RecordedSource& source, const RunOptions& opt, NoiseScales& s) {
  double q = 0;
  if (chi2_inv(opt.step.confidence, 2, q) != Status::kOk) throw std::runtime_error("bad confidence");
  // E[d2 | d2 < q] / 2 for a chi-square of 2 dof truncated at the gate.
  const double kappa = 1 - (q / 2) * std::exp(-q / 2) / (1 - std::exp(-q / 2));
  RecordedSource src = source;
  src.scale_noise(s.range, s.bearing, s.odometry);
  src.rewind();
  RunResult r = run_inputs(src, opt);
  const InnovationSums& in = r.innovations;
  if (in.n < 10) throw std::runtime_error("noise from the innovations: fewer than 10 pairings to learn from");
  const double n = static_cast<double>(in.n);
  const double rho0 = in.nis[0] / n / kappa, rho1 = in.nis[1] / n / kappa;
  s.range *= std::sqrt(rho0);
  s.bearing *= std::sqrt(rho1);
  s.odometry *= std::sqrt(std::sqrt(rho0 * rho1));
  return r;
}

}  // namespace geojcbb::host
