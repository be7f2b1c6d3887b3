// host_tools/runs: one EKF-SLAM run with a chosen association strategy: the run's options and
// presets (RunOptions, Method), the in-process session (SlamSession, node::SlamStep underneath) and
// run_inputs, which feeds it a source's inputs. The scorer is run_score.hpp's, the sources
// (simulator, recorded logs) run_source.hpp's.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb/core/presets.hpp"
#include "geojcbb/core/settings.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb_host/global_map.hpp"
#include "geojcbb_host/run_score.hpp"
#include "geojcbb_host/run_source.hpp"
#include "geojcbb_host/scene.hpp"

namespace geojcbb::host {

/// What one scan's observations became, for an observer of the run (RunOptions::on_scan): the
/// observations in the order the filter took them (the nearest first, at most kEvalMaxObservations),
/// and per observation the landmark id it was paired with (`paired`) or that was made from it
/// (`added`), kNewFeature where neither.
struct ScanOutcome {
  double t_s = 0;
  const std::vector<SimObservation>* scan = nullptr;
  const std::vector<FeatureId>* paired = nullptr;
  const std::vector<FeatureId>* added = nullptr;
};

/// What a run's steps made of each scan, recorded through RunOptions::on_scan: the observations as
/// the filter took them and per observation the landmark id it was paired with or made (or none).
/// The batch reference (host_tools/mapping, batch.hpp) is built from it.
class ScanRecorder {
 public:
  void on_scan(const ScanOutcome& s);
  struct Scan {
    double t_s = 0;
    std::vector<SimObservation> obs;
    std::vector<FeatureId> id;  ///< per observation: paired or made; kNewFeature where neither
  };
  const std::vector<Scan>& scans() const { return scans_; }

 private:
  std::vector<Scan> scans_;
};

/// A run's settings: the SLAM step's (one StepSettings, every option of core/options.h) and what only
/// the host knows. step_settings() applies the host's fields to the step's: the in-process filter and
/// a device over the link are configured from its result, so both run the same settings.
struct RunOptions {
  /// The step's options. local_radius_m, min_range_m, max_range_m and half_fov_rad are replaced by
  /// step_settings() from the run's sensor (r + d and the view below); the rest are used as set.
  StepSettings<double> step;
  double compensation_m = 5.0;  ///< d in r + d (eq. 5); r is the sensor's max range
  double view_margin_m = 1.0;   ///< a landmark within this of the range limits is not expected
  int max_steps = 0;            ///< stop after this many control intervals (0: the whole path)
  /// Known-map mode (localisation only): these true landmarks (index = truth) are the map from the
  /// start, with std known_map_sigma_m, and nothing is added or removed. Empty: SLAM.
  std::vector<Eigen::Vector2d> known_map;
  double known_map_sigma_m = 0.01;
  /// Optional: true landmark -> group, for RunResult::group_score (landmarks
  /// too close together for geometry to tell apart share a group). Empty:
  /// group_score equals score.
  std::vector<int> landmark_group;
  /// Pair by ground truth instead of running the strategy (gated at chi2(0.999, 2)): the filter's
  /// own accuracy with perfect association, a reference for the strategies.
  bool oracle = false;
  /// Record RunResult::trace, the pose estimate after every input.
  bool record_trace = false;
  /// Sequential map joining (docs/submaps.md): each local map the step closes (its closing rule,
  /// StepSettings::submap_*) is joined into a GlobalMap with these options, and the step restarts.
  /// The pose and map reported are the global ones.
  bool submaps = false;
  /// Before each scan, the local map is offered the global landmarks within r + d of the robot that
  /// it does not hold (GlobalMap::seed, at most kSeedsPerFrame), and takes those none of its own is
  /// compatible with, within its candidates and its capacity less a scan (node::seed_map; through a
  /// device, SUBMAP_SEED: docs/submaps.md, "Seed").
  bool submap_seed = false;
  JoinOptions join;
  std::string join_preset = "PCJCBB";  ///< join.preset's name (the command line's), read by step_settings
  /// Called after each scan's step with what its observations became (the MRCLAM report's split of
  /// the other robots' false pairs, mover_motion.hpp). In process only: a device's runner ignores it.
  std::function<void(const ScanOutcome&)> on_scan;
};

/// The closing rule of --submaps when none is given: the default device's map (96 landmarks) less
/// one scan of new landmarks (24), so the closing scan never meets a full map.
constexpr int kDefaultSubmapLandmarks = DefaultBounds::kMaxLandmarks - DefaultBounds::kMaxObservations;

/// The step's settings of a run with this sensor: opt.step with r + d = max range + compensation,
/// the view from the sensor's limits less the margin (and the FOV less 3 bearing sigma), and in
/// known-map mode augmentation off and the static gate at its default (off): known landmarks stay.
StepSettings<double> step_settings(const RunOptions& opt, const SensorModel& sensor);

/// The global map of a run with submaps: opt.join with the preset named by opt.join_preset and the
/// step's confidence. Throws std::invalid_argument for an unknown preset.
std::unique_ptr<GlobalMap> make_global_map(const RunOptions& opt, const StepSettings<double>& step);
/// A join's figures added to the run's (maps, offered, fused, declined, refused; a fused pair of two
/// different known truths, id_truth[id] >= 0, is a wrong join, and one within a group of
/// landmark_group, true landmark -> group, empty: none, is also counted in wrong_in_group) and its
/// record (SubmapStats::joins): its counts, the closing scan's time t_s, the map's worst step and the
/// global map's base after it.
void record_join(SubmapStats& st, const JoinResult& joined, const GlobalMap& global, double t_s,
                 const std::vector<int>& id_truth, const std::vector<int>& landmark_group, double worst_step_s);
/// The run's map is the global one: its landmarks with their truths (id_truth[first id], unknown when
/// out of range), the spurious count, landmarks and map_cov.
void take_global_map(RunResult& res, const GlobalMap& global, const std::vector<int>& id_truth);
/// A trace's poses composed again with their local maps' origins as the global map holds them now
/// (`local`: per trace point, its local map and the pose in that map's frame); nothing changes unless
/// the global map is a factor graph (dense: the origins are never revisited).
void smooth_trace(const GlobalMap& global, const std::vector<std::pair<int, Pose2<double>>>& local,
                  std::vector<TracePoint>& trace);

/// A row of the evaluation: a strategy, or the ground-truth association ("TRUTH").
/// Pieces switched into a preset are suffixes after "+": V the verification (e.g. "JCBB+V"), R
/// the relocaliser, L the loop-closure check, T tentative landmarks isolated, H the hypothesis
/// window (kPresetRivals kept beside the best), C clusters paired first: the grammar and its table
/// are core/presets.hpp's, read alike by every tool and by Python. kRobustPreset names the preset with V, R and L.
struct Method {
  Strategy strategy = Strategy::kGeojcbb;
  bool oracle = false;
  bool verify = false;      ///< AssociationConfig::verify switched into the preset
  bool relocalise = false;  ///< StepSettings::relocalise switched in
  bool loop_check = false;  ///< StepSettings::loop_check switched in
  bool tentative = false;   ///< StepSettings::tentative_isolated switched in
  bool window = false;      ///< StepSettings::hypothesis_rivals (kPresetRivals) switched in
  bool clusters = false;    ///< StepSettings::cluster_first switched in
  /// The preset's pieces as the grammar's table has them (core/presets.hpp).
  Preset preset() const {
    Preset p;
    p.strategy = strategy;
    const bool on[] = {verify, relocalise, loop_check, tentative, window, clusters};  // kPresetSuffixes' order
    static_assert(sizeof(on) / sizeof(on[0]) == kPresetSuffixCount, "a Method field per suffix");
    for (int k = 0; k < kPresetSuffixCount; ++k) p.suffixes = static_cast<std::uint8_t>(p.suffixes | (on[k] << k));
    return p;
  }
  static Method from(const Preset& p) {
    return {p.strategy, false, p.has('V'), p.has('R'), p.has('L'), p.has('T'), p.has('H'), p.has('C')};
  }
  std::string name() const {
    if (oracle) return "TRUTH";
    char buf[kMaxPresetName + 1];
    preset_name(preset(), buf);
    return buf;
  }
  void apply(RunOptions& o) const {
    apply_preset(preset(), o.step);
    o.oracle = oracle;
  }
};

/// The preset with every piece of the lost-and-found work: PCJCBB (pose-free verification), the
/// relocaliser and the loop-closure check (docs/relocalisation.md).
constexpr const char* kRobustPreset = "PCJCBB+RL";

/// The tools' one strategy-list parser (geojcbb_eval, geojcbb_link, geojcbb_qemu, the benchmarks):
/// each name read by parse_strategy (case-insensitive; "+V" switches the verification in, e.g.
/// "JCBB+V"), in the order given; no names: every preset (`all_presets`) or the papers' six. `oracle`
/// appends the TRUTH row. Throws std::invalid_argument naming an unknown strategy.
/// The presets as the tools' help texts name them.
constexpr const char* kPresetsHelp =
    "ICNN, JCBB, KJCBB, DFJCBB, GEMJCBB, GEOJCBB, PCJCBB, each optionally with +V (verification), +R (relocaliser), "
    "+L (loop-closure check), +T (tentative landmarks isolated), +H (hypothesis window), +C (clusters paired "
    "first) or a combination (+VRLTHC); PCJCBB+RL is the robust preset";
std::vector<Method> select_methods(const std::vector<std::string>& names, bool all_presets, bool oracle = false);

/// The in-process filter's capacity (SlamSession): observations per scan, landmarks in the map.
constexpr int kEvalMaxObservations = 48, kEvalMaxLandmarks = 1000;

/// One EKF-SLAM run fed step by step (the simulator and the MRCLAM replay both
/// drive it): predict with odometry; per scan associate, score against the
/// observations' truth, update, augment and review the landmarks. Host
/// capacity: 48 observations per scan (the nearest are kept), 128 candidates,
/// kEvalMaxLandmarks landmarks. A full map is not an error: new landmarks are then refused and
/// counted (RunResult::not_augmented), as on the device. Throws std::runtime_error when a
/// library call fails (the message names the call and its status).
class SlamSession {
 public:
  SlamSession(const RunOptions& options, const SensorModel& sensor, std::size_t true_landmarks, const Pose2<double>& x0,
              const Eigen::Matrix3d& P0);
  ~SlamSession();
  SlamSession(const SlamSession&) = delete;
  SlamSession& operator=(const SlamSession&) = delete;

  void predict(double v_mps, double w_radps, double dt_s, double sigma_v_mps, double sigma_w_radps);
  /// A pose increment (dx, dy, dtheta) in the robot's frame, with its covariance.
  void predict(double dx_m, double dy_m, double dtheta_rad, const Eigen::Matrix3d& cov);
  /// The robot was carried: its pose covariance re-set to P (the estimate kept), the map kept.
  void relocalise(const Eigen::Matrix3d& P);
  /// One scan; each observation's truth is a landmark index < true_landmarks,
  /// or -1 for clutter. `truth` is the true pose at the scan, for the pose
  /// error and NEES (nullptr: not recorded).
  void scan(std::vector<SimObservation> scan, double t_s, const Pose2<double>* truth);
  Pose2<double> pose() const;
  /// The pose in the world appended to `trace` at time t; with local maps, remembered in its local
  /// map's frame too, for smoothed().
  void trace(double t, std::vector<TracePoint>& trace);
  /// With local maps: the trace's poses again through the global map's origins of their local maps
  /// as they are now (kGraph: relinearised by every later join; dense: as they were).
  void smoothed(std::vector<TracePoint>& trace) const;
  /// The result so far; finish() adds the final map and the means.
  RunResult finish();

  struct State;

 private:
  std::unique_ptr<State> st_;
};

/// Runs a source's inputs through a SlamSession. Throws as SlamSession does.
RunResult run_inputs(RunSource& src, const RunOptions& opt);

/// Noise from the innovations (docs/replay.md, "Noise from the innovations"): factors on the
/// variances of every measurement's R (range, bearing) and of every prediction's noise.
struct NoiseScales {
  double range = 1, bearing = 1, odometry = 1;
};
/// One round of the NIS matched to its expectation: replays `source` with its noise scaled by `s`
/// (RecordedSource::scale_noise) under `opt`, then moves `s` half-way (in log space) to where each
/// component's mean NIS of the pairs, nu_k^2 / S_kk corrected for the individual gate's truncation,
/// would be 1. Scaling R and the odometry noise by one factor c scales P and S by c once the pairs
/// are fixed, so that NIS says by how much: R's k-th variance by rho_k, the odometry's by the
/// geometric mean of rho_range and rho_bearing. Half a step per round: a narrower gate changes the
/// pairs, so the next round measures again. Throws with fewer than 10 pairings.
/// @return the round's run (its innovations and NIS as measured at the scales it was given)
RunResult innovation_round(const RecordedSource& source, const RunOptions& opt, NoiseScales& s);
/// Who runs a run's inputs: run_inputs in process, or a device over the link (geojcbb_eval --port).
using RunInputsFn = std::function<RunResult(RunSource&, const RunOptions&)>;

/// Runs one seed of one scenario. Throws std::runtime_error when the map
/// capacity is exceeded or a library call fails (the message names the call and
/// its status).
RunResult run_slam(const Scenario& scenario, std::uint64_t seed, const RunOptions& options);

}  // namespace geojcbb::host
