// host_tools/eval: one EKF-SLAM run over a simulated scenario with a chosen
// association strategy, scored against the simulator's ground truth with the
// papers' definitions (2019 paper, eqs. 15-19):
//   TP  a pair whose map feature was initialised from the observation's true
//   landmark FP  any other pair (wrong feature, or clutter paired) FN  an
//   observation of a mapped landmark left unpaired TN  an observation correctly
//   left unpaired: clutter, or a landmark not yet in the map
// Every observation falls in exactly one class, so Total = TP + TN + FP + FN
// (eq. 15). (The association benchmarks count recall against ground-truth pairs
// instead, where a wrong pair of a mapped landmark is also a missed one.)
// Augmentation rule: an observation with no compatible candidate (kNewFeature)
// becomes a landmark only if its nearest d2 also exceeds a second, wider gate
// (chi2(0.999, 2) by default); between the two gates it is too close to a
// mapped feature to be new and too far to pair, and is dropped. A new landmark
// is tentative until it is paired again; expected in view and missed twice
// before that, it leaves the map (ekf::LandmarkPolicy). Clutter that passes the
// second gate is rarely seen twice in one place, so it is gone a few scans
// later; landmark ids stay stable throughout.
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
#include "geojcbb_host/scene.hpp"
#include "geojcbb_host/sim.hpp"

namespace geojcbb::host {

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
};

struct SensorModel;

/// The step's settings of a run with this sensor: opt.step with r + d = max range + compensation,
/// the view from the sensor's limits less the margin (and the FOV less 3 bearing sigma), and in
/// known-map mode augmentation off with every landmark rule at its default but confirm_hits = 1.
StepSettings<double> step_settings(const RunOptions& opt, const SensorModel& sensor);

struct MapLandmark {
  double x, y;
  int truth;  ///< true landmark index, or -1 when made from clutter
};

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

/// The pose estimate at a time.
struct TracePoint {
  double t_s;
  Pose2<double> pose;
};

struct StepRecord {
  double t_s;
  Pose2<double> truth, estimate;
  double var_x, var_y;          ///< pose variances [m^2]
  double pose_nees;             ///< (x, y, theta) NEES
  double var_theta = 0;         ///< heading variance [rad^2]
  int paired = 0;               ///< pairings of the scan
  double nis_sum = 0;           ///< sum of their individual NIS (d2, 2 dof each)
  int tp = 0, fp = 0;           ///< correct and false pairings of the scan
  double assoc_s = 0;           ///< the scan's association time
  bool lost = false;            ///< the relocaliser's state after the scan: lost
  bool declared_found = false;  ///< the relocaliser confirmed its pose at this scan (found)
};

struct RunResult {
  Score score;
  Score group_score;  ///< as score, but a pair is correct when its feature's
                      ///< landmark is in the same group
  int scans = 0;
  int observations = 0;  ///< scored observations (= TP + TN + FP + FN)
  int fp_clutter = 0;    ///< of the FP, clutter (other robots, false detections) paired
  /// Of the FP of a true landmark's observation paired with another true landmark's map landmark:
  /// that map landmark is a duplicate (made after the first one of its identity, e.g. during a
  /// drift), or the first (the original) of its identity.
  int fp_to_duplicate = 0, fp_to_original = 0;
  /// The same FP (and those paired with a landmark made from clutter) by where the map landmark is:
  /// another true landmark of the observed one's group (MRCLAM: a neighbour in a row of tubes), or
  /// elsewhere (another group, or clutter's). Without groups every one is elsewhere.
  int fp_in_group = 0, fp_other_group = 0;
  int landmarks = 0;                   ///< mapped at the end
  int spurious_landmarks = 0;          ///< augmented from clutter (over the run)
  int spurious_in_map = 0;             ///< made from clutter and still mapped at the end
  int removed_spurious_landmarks = 0;  ///< tentative landmarks from clutter removed
  int removed_true_landmarks = 0;      ///< tentative landmarks of true landmarks removed
  std::vector<MapLandmark> map;        ///< the final map
  int dropped_observations = 0;        ///< over the observation capacity in a scan
  int not_augmented = 0;               ///< would have become landmarks, but the map was full (not added)
  int evicted = 0;                     ///< landmarks evicted to make room (evict_when_full)
  int budget_hits = 0;                 ///< scans whose JCBB node budget ran out
  int relocalisations = 0;             ///< poses the relocaliser accepted
  int loop_commits = 0;                ///< loop closures the closure check committed (loop_check)
  int loop_held_scans = 0;             ///< scans whose disputed pairs it held (a pending closure)
  int windows = 0;                     ///< hypothesis windows opened (hypotheses)
  int window_commits = 0;              ///< windows that committed a leader
  int window_held_scans = 0;           ///< scans a window was open (the opening one included)
  int regrouped = 0;                   ///< observations cluster_first paired anew
  int merges = 0;                      ///< duplicates merged after a closure (loop_merge_d2)
  double association_s = 0;            ///< total association time
  double mean_abs_x_m = 0,
         mean_abs_y_m = 0;        ///< over the scans with a true pose
  std::vector<StepRecord> steps;  ///< one per scan with a true pose
  /// Every scan's pairings and the sum of their NIS (d2, 2 dof each), with or without a true pose.
  long nis_pairings = 0;
  double nis_sum = 0;
  /// The pose estimate after every input (RunOptions::record_trace): what a real log without a
  /// true pose is scored by (GPS, trace.hpp).
  std::vector<TracePoint> trace;
};

/// The sensor as the filter knows it, for the local region and for which
/// landmarks are expected.
struct SensorModel {
  double min_range_m = 0, max_range_m = 30, fov_rad = 3.14159265358979, sigma_bearing_rad = 0.0175;
  /// Where the sensor sits on the robot (core/range_bearing.hpp's Mount): used where the run's
  /// options give no mount of their own.
  double x_m = 0, y_m = 0, theta_rad = 0;
};

/// The evaluation's scoring of one run, in one place: the in-process SlamSession and a device's
/// replies over the serial link (host_tools/link) both use it. Per scan, score() classifies each
/// observation (TP/FP/FN/TN, and the same at landmark-group level) from its truth and the landmark it
/// was paired with; added() and removed() keep the map's landmark ids -> true landmarks; pose()
/// records the pose error and the (x, y, theta) NEES; finish() takes the means.
class RunScorer {
 public:
  /// Truth of a landmark id that has left the map, and of an id never reported as added.
  static constexpr int kRemoved = -2, kUnknown = -3;
  /// @param landmark_group  true landmark -> group (empty: each landmark its own group)
  RunScorer(std::size_t true_landmarks, std::vector<int> landmark_group);
  /// One scan, before the filter's update. truth[i]: the observation's true landmark (index, or -1
  /// for clutter); paired[i]: the landmark id it was paired with, or < 0 when not paired.
  void score(const std::vector<int>& truth, const std::vector<FeatureId>& paired);
  /// Landmark `id` was made from an observation of true landmark `truth` (-1: clutter).
  void added(FeatureId id, int truth);
  /// Landmark `id` left the map (tentative, missed in view).
  void removed(FeatureId id);
  /// True landmark of `id`: an index, -1 (clutter), kRemoved, or kUnknown.
  int truth_of(FeatureId id) const;
  /// Landmark ids handed out so far (ids are 0, 1, ... in order of creation).
  std::size_t ids() const { return feature_truth_.size(); }
  /// The pose estimate at a scan against the truth; P over (x, y, theta).
  void pose(double t_s, const Pose2<double>& truth, const Pose2<double>& estimate, const Eigen::Matrix3d& P);
  /// The scan just recorded by pose(): its pairings and the sum of their NIS.
  void nis(int paired, double nis_sum);
  RunResult& result() { return res_; }
  /// The result with mean_abs_x_m / mean_abs_y_m divided by the scans with a true pose.
  RunResult finish() const;

 private:
  int cls(int t) const { return landmark_group_.empty() ? t : landmark_group_[static_cast<std::size_t>(t)]; }
  std::vector<int> feature_truth_;   ///< landmark id -> true landmark it came from (-1 clutter)
  std::vector<int> mapped_;          ///< true landmark -> map landmarks made from it, still mapped
  std::vector<FeatureId> first_;     ///< true landmark -> the first map landmark made from it (-1: none)
  std::vector<int> landmark_group_;  ///< true landmark -> its group
  RunResult res_;
};

/// A scan's pose is right: within 1 m and 5 degrees of the truth, and each of x, y, theta within 3
/// sigma of its variance.
bool pose_right(const StepRecord& k);

/// A kidnap scene (kidnap at kidnap_t_s), scored by the pose, not by the pairings alone.
struct KidnapScore {
  /// The first scan after the kidnap (counted from 1) from which on, for `window` scans (fewer at the
  /// run's end), the pose is right (pose_right) and no pairing is false: the robot has found itself
  /// there. 0: never. (A window, not the rest of the run: a clutter return paired a minute later is
  /// not a failure to relocalise.)
  int found_at = 0;
  /// The relocaliser declared itself found at a scan whose pose was not right.
  bool false_relocalisation = false;
  double pose_error_after_m = 0;  ///< mean position error over the scans after the kidnap [m]
  double anees_before = 0;        ///< mean NEES over the scans before the kidnap
  double anees_after = 0;         ///< ... and after it
};
KidnapScore kidnap_score(const RunResult& r, double kidnap_t_s, int window = 10);

/// One input of a run, in time order: a prediction (odometry over dt and its noise) or a scan.
struct RunInput {
  bool scan = false;
  double v_mps = 0, w_radps = 0, dt_s = 0, sigma_v_mps = 0, sigma_w_radps = 0;  ///< prediction
  /// The prediction is a pose increment (dx, dy, dtheta in the robot's frame at its start, with
  /// its covariance increment_cov) instead of (v, w) over dt_s.
  bool increment = false;
  double dx_m = 0, dy_m = 0, dtheta_rad = 0;
  Eigen::Matrix3d increment_cov = Eigen::Matrix3d::Zero();
  std::vector<SimObservation> observations;  ///< scan: (range, bearing), each with its truth and R
  double t_s = 0;                            ///< scan time (a prediction's start where known)
  bool have_truth = false;                   ///< true_pose is known
  Pose2<double> true_pose{};
  /// A kidnap: the filter's pose covariance re-set to pose_cov, the estimate kept (no prediction,
  /// no scan in this input).
  bool relocalise = false;
  Eigen::Matrix3d pose_cov = Eigen::Matrix3d::Identity();
};

/// A run's inputs (the simulator's, or a MRCLAM robot's log) with what the filter starts from; fed
/// to the in-process filter (run_inputs) or streamed to a device (host_tools/link, stream_run).
class RunSource {
 public:
  virtual ~RunSource() = default;
  /// The next input; false after the last.
  virtual bool next(RunInput& in) = 0;
  /// Back to the first input (a run that restarts gives the same inputs again).
  virtual void rewind() = 0;
  SensorModel sensor;
  std::size_t true_landmarks = 0;
  Pose2<double> x0{};
  Eigen::Matrix3d P0 = Eigen::Matrix3d::Identity();
};

/// Inputs held in memory: a MRCLAM replay's, or another source's recorded (so a benchmark times
/// the filter or the link, not the simulator).
class RecordedSource : public RunSource {
 public:
  RecordedSource() = default;
  /// Every input of `src` (from its current position), with its sensor and start.
  explicit RecordedSource(RunSource& src);
  bool next(RunInput& in) override;
  void rewind() override { at_ = 0; }
  const std::vector<RunInput>& inputs() const { return inputs_; }

 protected:
  std::vector<RunInput> inputs_;

 private:
  std::size_t at_ = 0;
};

/// The simulator's inputs for one seed: per control interval a prediction, then the scan when one
/// was taken. At most max_steps control intervals (0: the whole path).
class SimSource : public RunSource {
 public:
  SimSource(const Scenario& scenario, std::uint64_t seed, int max_steps = 0);
  ~SimSource() override;
  bool next(RunInput& in) override;
  void rewind() override;
  /// The prediction of a simulator step: its odometry over the scenario's dt and noise.
  static RunInput prediction(const Scenario& scenario, const SimStep& step);

 private:
  const Scenario& sc_;
  std::uint64_t seed_;
  int max_steps_;
  std::unique_ptr<Simulator> sim_;
  SimStep step_;
  long k_ = 0;
  bool scan_due_ = false;
  bool kidnap_due_ = false;
};

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
  /// The result so far; finish() adds the final map and the means.
  RunResult finish();

  struct State;

 private:
  std::unique_ptr<State> st_;
};

/// Runs a source's inputs through a SlamSession. Throws as SlamSession does.
RunResult run_inputs(RunSource& src, const RunOptions& opt);
/// Who runs a run's inputs: run_inputs in process, or a device over the link (geojcbb_eval --port).
using RunInputsFn = std::function<RunResult(RunSource&, const RunOptions&)>;

/// Runs one seed of one scenario. Throws std::runtime_error when the map
/// capacity is exceeded or a library call fails (the message names the call and
/// its status).
RunResult run_slam(const Scenario& scenario, std::uint64_t seed, const RunOptions& options);

}  // namespace geojcbb::host
