// host_tools/runs: the inputs of a run, in time order (predictions and scans), from the simulator
// (SimSource) or held in memory (RecordedSource: a log's, or another source's recorded), with the
// sensor and the start the filter is given; fed to the in-process session (slam_run.hpp) or streamed
// to a device (host_tools/link).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "geojcbb/core/math.hpp"
#include "geojcbb_host/scene.hpp"
#include "geojcbb_host/sim.hpp"

namespace geojcbb::host {

/// The sensor as the filter knows it, for the local region and for which
/// landmarks are expected.
struct SensorModel {
  double min_range_m = 0, max_range_m = 30, fov_rad = 3.14159265358979, sigma_bearing_rad = 0.0175;
  /// Where the sensor sits on the robot (core/range_bearing.hpp's Mount): used where the run's
  /// options give no mount of their own.
  double x_m = 0, y_m = 0, theta_rad = 0;
};

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
  /// Every measurement's R scaled by (range_var, bearing_var) on its diagonal (the correlation kept)
  /// and every prediction's noise covariance by odometry_var (replay --noise-from-innovations).
  void scale_noise(double range_var, double bearing_var, double odometry_var);

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

}  // namespace geojcbb::host
