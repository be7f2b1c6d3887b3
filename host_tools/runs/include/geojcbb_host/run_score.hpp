// host_tools/runs: the scoring of one EKF-SLAM run (the in-process session's and a device's), against the simulator's ground truth with the
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

#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <vector>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb_host/join_counts.hpp"
#include "geojcbb_host/run_counters.hpp"
#include "geojcbb_host/scene.hpp"

namespace geojcbb::host {

struct MapLandmark {
  double x, y;
  int truth;  ///< true landmark index, or -1 when made from clutter
  /// The nearest range it was observed at (made or paired) [m]; infinity where not recorded (the
  /// global map of --submaps).
  double closest_m = std::numeric_limits<double>::infinity();
};

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
  /// The estimate and its covariance set, with the variances and the NEES against `truth`.
  /// @return the error (x, y, theta).
  Eigen::Vector3d set_estimate(const Pose2<double>& x, const Eigen::Matrix3d& P);
};

/// Sums over a run's pairings of each innovation component k (0 range, 1 bearing): nis = nu_k^2 / S_kk
/// (S = H P H^T + R, the pair's innovation covariance; its mean is 1 for a consistent filter), and
/// the share of S that is R, r = R_kk / S_kk (replay --noise-from-innovations, docs/replay.md).
struct InnovationSums {
  long n = 0;
  double nis[2] = {0, 0}, r_share[2] = {0, 0};
};

/// Sequential map joining's figures (RunOptions::submaps).
/// One join as a run records it (SubmapStats::joins; replay writes them to joins.csv).
struct JoinRecord : JoinCounts {
  double t_s = 0;                 ///< the closing scan's time
  double worst_step_s = 0;        ///< the map's slowest step (0: not timed, as through a device)
  int global = 0;                 ///< the global map's landmarks after the join
  double base[3] = {0, 0, 0};     ///< the next map's origin (this map's last pose) in the global frame
  double base_sd[3] = {0, 0, 0};  ///< its standard deviations [m, m, rad]
};

struct SubmapStats {
  int maps = 0;                   ///< local maps joined
  int offered = 0;                ///< their landmarks with a compatible global one
  int fused = 0;                  ///< landmarks fused with a global one
  int declined = 0;               ///< ambiguous pairings left out
  int removed = 0;                ///< global landmarks removed by a local map's evidence (seeds it removed)
  int refused = 0;                ///< joins refused (their pairs not jointly compatible)
  int wrong = 0;                  ///< fused pairs of two different true landmarks (labelled data)
  int wrong_in_group = 0;         ///< of those, two of one landmark group (closer than the sensor separates)
  int seeded = 0;                 ///< global landmarks the local maps took as seeds (--submap-seed)
  std::vector<JoinRecord> joins;  ///< per local map: what its join did
  // Through a device (stream_run):
  int frames = 0;                  ///< SUBMAP and SUBMAP_COV frames received (one sending per map)
  int requests = 0;                ///< maps asked for again (frames lost)
  std::vector<double> handover_s;  ///< per map: from its last POSE to the device's ACK of SUBMAP_ACK
};

struct RunResult {
  Score score;
  SubmapStats submaps;
  Score group_score;  ///< as score, but a pair is correct when its feature's
                      ///< landmark is in the same group
  int scans = 0;
  int observations = 0;  ///< scored observations (= TP + TN + FP + FN)
  /// The counters of GEOJCBB_RUN_COUNTERS. Of the FP of a true landmark's observation paired with
  /// another true landmark's map landmark: that map landmark is a duplicate (made after the first
  /// one of its identity, e.g. during a drift), or the first (the original) of its identity; the
  /// same FP (and those paired with a landmark made from clutter) by where the map landmark is:
  /// another true landmark of the observed one's group, or elsewhere. Without groups every one is
  /// elsewhere.
  GEOJCBB_RUN_COUNTERS(GEOJCBB_RUN_COUNTER_MEMBER)
  int landmarks = 0;                   ///< mapped at the end
  int spurious_landmarks = 0;          ///< augmented from clutter (over the run)
  int spurious_in_map = 0;             ///< made from clutter and still mapped at the end
  int removed_spurious_landmarks = 0;  ///< tentative landmarks from clutter removed
  int removed_true_landmarks = 0;      ///< tentative landmarks of true landmarks removed
  std::vector<MapLandmark> map;        ///< the final map
  Eigen::MatrixXd map_cov;             ///< its landmarks' joint covariance (2 per landmark, map's order)
  double association_s = 0;            ///< total association time
  double mean_abs_x_m = 0,
         mean_abs_y_m = 0;        ///< over the scans with a true pose
  std::vector<StepRecord> steps;  ///< one per scan with a true pose
  /// Every scan's pairings and the sum of their NIS (d2, 2 dof each), with or without a true pose.
  long nis_pairings = 0;
  double nis_sum = 0;
  InnovationSums innovations;  ///< every pairing's innovation, per component (noise from innovations)
  /// The world model at the end of the run (ekf/detection.hpp): p_D per range bin (learn_detection;
  /// empty without), each bin pd_bin_m wide, and the clutter density (learn_clutter; 0 without).
  std::vector<double> learned_pd;
  double pd_bin_m = 0;
  double clutter_density = 0;
  /// The pose estimate after every input (RunOptions::record_trace): what a real log without a
  /// true pose is scored by (GPS, trace.hpp).
  std::vector<TracePoint> trace;
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
  /// for clutter and movers); paired[i]: the landmark id it was paired with, or < 0 when not paired;
  /// mover[i] (empty: none): the simulated mover it saw (its truth -1: a pair is false, counted in
  /// fp_clutter and fp_mover), or -1.
  void score(const std::vector<int>& truth, const std::vector<FeatureId>& paired, const std::vector<int>& mover = {});
  /// Landmark `id` was made from an observation of true landmark `truth` (-1: clutter or a mover);
  /// mover >= 0: of that simulated mover (counted in movers_in_map while it stays mapped).
  void added(FeatureId id, int truth, int mover = -1);
  /// Landmark `id` left the map (tentative, missed in view).
  void removed(FeatureId id);
  /// Landmark `id` left the local map with it, handed over (RunOptions::submaps): no longer mapped
  /// here, and not counted as removed.
  void handed_over(FeatureId id);
  /// True landmark of `id`: an index, -1 (clutter), kRemoved, or kUnknown.
  int truth_of(FeatureId id) const;
  /// Landmark ids handed out so far (ids are 0, 1, ... in order of creation).
  std::size_t ids() const { return feature_truth_.size(); }
  /// The pose estimate at a scan against the truth; P over (x, y, theta).
  void pose(double t_s, const Pose2<double>& truth, const Pose2<double>& estimate, const Eigen::Matrix3d& P);
  /// The scan just recorded by pose(): its pairings and the sum of their NIS.
  void nis(int paired, double nis_sum);
  RunResult& result() { return res_; }
  /// The result with mean_abs_x_m / mean_abs_y_m divided by the scans with a true pose, and
  /// movers_in_map counted (the landmarks made from a mover still mapped here; handed-over ones are
  /// not, so with joined local maps it counts the last map's only).
  RunResult finish() const;

 private:
  int cls(int t) const { return landmark_group_.empty() ? t : landmark_group_[static_cast<std::size_t>(t)]; }
  std::vector<int> feature_truth_;   ///< landmark id -> true landmark it came from (-1 clutter)
  std::vector<int> feature_mover_;   ///< landmark id -> the mover it came from, or -1
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

}  // namespace geojcbb::host
