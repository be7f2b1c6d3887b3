// host_tools/runs: EKF-SLAM on the UTIAS MRCLAM real data (docs/mrclam.md),
// scored like the simulation. One run = one robot of one dataset with one
// strategy:
//   - start at the ground-truth pose at the first time both odometry and ground
//   truth exist, so
//     the map is in the Vicon frame and landmark and pose errors are read
//     directly;
//   - each odometry command (v, w) holds until the next sample (about 67 Hz); a
//   scan at time t
//     predicts up to t first. Across a gap in the log longer than kHoldLimit_s
//     the command is held for kHoldLimit_s and the robot then assumed stopped
//     (the log resumes with a stop command);
//   - a scan is the measurements of one camera frame (mrclam::load_robot groups
//   them); truth of a
//     measurement: the landmark's index when its barcode maps to a landmark
//     subject, else -1 (unknown barcodes and other robots are clutter);
//   - R = diag(sigma_range^2, sigma_bearing^2) and the odometry noise come from
//   the data unless
//     given (MrclamNoise::from_data; how: docs/mrclam.md).
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "geojcbb_host/mrclam.hpp"
#include "geojcbb_host/map_merge.hpp"
#include "geojcbb_host/mrclam_calibration.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host {

constexpr double kHoldLimit_s = 0.25;
/// With the calibrated drive, a gap in the log is driven through with the held command; this is the
/// std of the motion over the gap's rest as a fraction of that motion (docs/mrclam.md).
constexpr double kGapMotionStd = 0.2;
/// MRCLAM's landmarks stand in clusters of two or three, 0.13 - 0.28 m apart:
/// at the camera's range noise geometry cannot tell them apart. Landmarks
/// within this distance form a group for the group-level score
/// (docs/mrclam.md).
constexpr double kLandmarkGroupRadius_m = 0.35;

/// The groups themselves: replay::landmark_groups (event_log.hpp), on the log's landmark lines.

/// Noise the filter assumes on MRCLAM. The odometry sigmas are rates: over dt
/// the filter's (v, w) standard deviations are sigma * sqrt(1 s / dt), so the
/// variance of a displacement grows with time and not with the number of
/// samples.
struct MrclamNoise {
  double sigma_range_m = 0, sigma_bearing_rad = 0;
  double sigma_v_mps = 0,
         sigma_w_radps = 0;  ///< std of the 1-second mean of v and w
  /// Robust (MAD) spreads of the measurement residuals and of the 1-second
  /// odometry residuals of `robots`, each multiplied by `inflation`.
  static MrclamNoise from_data(const mrclam::Dataset& ds, const std::vector<mrclam::RobotLog>& robots,
                               double inflation);
};

/// The model the filter assumes on a robot's log: the constant noise of MrclamNoise, or parts of
/// the robot's calibration (mrclam_calibration.hpp), each switchable so its contribution can be
/// measured alone (docs/mrclam.md):
///   camera  z corrected for the range and bearing bias, R = diag((s_r0 + k_r r)^2, s_b^2) x inflation^2
///   drive   commands delayed by the latency and scaled; process noise of ekf::OdometryModel
///           x inflation^2; a log gap is driven through with the held command (kGapMotionStd)
struct MrclamModel {
  MrclamNoise noise;  ///< where a part below is off
  bool camera = false;
  bool drive = false;
  double inflation = 1.0;                ///< on the calibrated standard deviations
  mrclam::RobotCalibration calibration;  ///< of this robot
};

/// The camera as the filter knows it (README: range 0.9 - 9.3 m, bearing within
/// about +-0.6 rad).
SensorModel mrclam_sensor(const MrclamNoise& n);

/// One robot's log as a run's inputs: predictions from the odometry (held as described above) and
/// one scan per camera frame, R from the noise, the truth pose where ground truth covers the time.
/// Throws std::runtime_error for a log without odometry or ground truth.
class MrclamSource : public RecordedSource {
 public:
  MrclamSource(const mrclam::Dataset& ds, const mrclam::RobotLog& log, const MrclamModel& model,
               bool drop_other_robots = false);
  /// Per scan input, in input order: the subject of each of its observations (Measurement::subject;
  /// the truth says only "clutter" for another robot, the mover split needs which one).
  std::vector<std::vector<int>> scan_subjects;
};

/// One robot's replay. Throws std::runtime_error as run_slam does.
/// drop_other_robots: measurements of robots (subjects 1-5) are removed before
/// association instead of being fed as clutter.
RunResult replay_robot(const mrclam::Dataset& ds, const mrclam::RobotLog& log, const RunOptions& options,
                       const MrclamModel& model, bool drop_other_robots = false);

/// The run options MRCLAM replays start from: the landmark rules that keep the other robots and
/// the missed pairings out of the map (docs/mrclam.md measures each): the miss-probability rule at
/// 1e-5, the static gate at chi2(0.95, 2), a new landmark when every compatible one is taken, and a
/// landmark hidden behind a nearer one within 0.03 rad not expected (the tubes stand in rows).
RunOptions mrclam_run_defaults();

/// One robot's model as the report builds it.
MrclamModel mrclam_model(const MrclamNoise& noise, const mrclam::RobotCalibration& calibration, bool camera = true,
                         bool drive = true, double inflation = 1.2);

struct MrclamOptions {
  std::string data_dir;  ///< empty: mrclam::default_data_dir()
  /// Non-empty: one CSV per replay in this folder (trace_<dataset>_<robot>_<strategy>.csv: per scan
  /// the pose error, its variances, NEES, pairings and their NIS).
  std::string trace_dir;
  std::vector<int> datasets{6, 7};
  std::vector<int> robots{1, 2, 3, 4, 5};
  std::vector<Method> strategies;
  RunOptions run = mrclam_run_defaults();
  double sigma_range_m = 0, sigma_bearing_rad = 0;  ///< 0: from the data
  double sigma_v_mps = 0, sigma_w_radps = 0;        ///< 0: from the data
  double noise_inflation = 1.5;                     ///< on the data's robust spreads (their tails are heavy)
  int jobs = 0;                                     ///< worker threads (0: the number of cores)
  bool drop_other_robots = false;                   ///< see replay_robot
  bool known_map = false;                           ///< the surveyed landmarks as a fixed map (localisation only)
  bool camera = true;                               ///< MrclamModel::camera
  bool drive = true;                                ///< MrclamModel::drive
  double model_inflation = 1.2;                     ///< MrclamModel::inflation
  /// Where each robot's calibration is fitted: "cross" (the same robot in the other dataset, 6 <-> 7;
  /// nothing scored is used to fit) or "same" (the log that is replayed).
  std::string calibration = "cross";
  mrclam::CalibrationOptions calibration_options;
  /// --merge: per data set and strategy, the robots' final maps merged into one with their start
  /// poses unknown (map_merge.hpp); the merged map, its wrong joins and the starts found are printed.
  bool merge = false;
  /// > 0: each robot's first `seconds` only, from its first odometry sample (replay::truncate); the
  /// noise and the calibration are the whole logs' (what a full run uses).
  double seconds = 0;
  MergeOptions merge_options;
  /// Runs each replay's inputs (empty: in process, run_inputs); a device over the link needs jobs = 1.
  RunInputsFn runner;
  /// --batch (set by the command line, which links the batch reference: host_tools/mapping): per
  /// replay, from its source, what its steps made of each scan, its result (with its trace) and its
  /// settings, the mean position error [m] of the replay's trace, of the batch with its own pairings
  /// and of the batch with the labels. Empty: no batch.
  std::function<std::array<double, 3>(RunSource&, const ScanRecorder&, const RunResult&, const RunOptions&)> batch;
};

}  // namespace geojcbb::host
