// host_tools/mapping: the batch reference (docs/mapping.md, "The batch reference"). Every pose of a
// run (one at each scan) and every landmark solved at once by sparse nonlinear least squares
// (Ceres Solver, its sparse Cholesky), with a given association: the one a preset made (the ids its
// steps paired or made) or the labels of the data. It says how far a filter's figure is from what
// the data and that association allow: the filter linearises once and never revisits; the batch
// relinearises every pose and landmark until it converges.
//
// The problem: pose 0 fixed at the filter's start; between consecutive scans one odometry factor,
// the predictions between them composed in the first scan's frame with their covariance (the
// filter's motion model, ekf/motion.hpp); per observation one range-bearing factor through the
// sensor's mount, weighted by its R; a Huber loss on the observations optional (a wrong pair of the
// association then pulls less). A kidnap (RunInput::relocalise) breaks the odometry chain there.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb_host/run_score.hpp"
#include "geojcbb_host/run_source.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host {

struct BatchObservation {
  int pose = 0;      ///< the scan's index
  int landmark = 0;  ///< the landmark's index in the problem
  Eigen::Vector2d z = Eigen::Vector2d::Zero();
  Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
};

struct BatchProblem {
  Mount<double> mount;
  std::vector<double> t_s;              ///< per pose: its scan's time
  std::vector<Pose2<double>> initial;   ///< per pose: the start (the filter's estimate after the scan)
  std::vector<char> have_truth;         ///< per pose: the log gives its true pose (truth)
  std::vector<Pose2<double>> truth;     ///< per pose: the true pose, where have_truth
  std::vector<Pose2<double>> relative;  ///< per pose but the first: the odometry from the one before, in its frame
  std::vector<Eigen::Matrix3d> relative_cov;
  std::vector<char> chained;  ///< per pose but the first: 0 where a kidnap broke the chain (no factor)
  std::vector<BatchObservation> obs;
  std::vector<Eigen::Vector2d> landmark_initial;  ///< per landmark: from its first observation
  /// The path between the scans, for the trace at every input (as the filter's): per input after
  /// the first scan, its time, the last scan at or before it, and the odometry since that scan.
  struct Between {
    double t_s = 0;
    int pose = 0;
    Pose2<double> rel{};
  };
  std::vector<Between> path;
};

struct BatchOptions {
  /// Huber's threshold on an observation's whitened residual (its norm, in sigmas); 0: plain least
  /// squares.
  double huber = 0;
  int max_iterations = 200;
};

struct BatchResult {
  std::vector<Pose2<double>> poses;        ///< the solved pose at each scan
  std::vector<TracePoint> trace;           ///< at every input: the scans' poses, and between them (Between)
  std::vector<Eigen::Vector2d> landmarks;  ///< the solved landmarks
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;  ///< Ceres' cost: half the sum of squared whitened residuals
  bool converged = false;
  double solve_s = 0;
  std::string report;  ///< Ceres' brief report
};

/// What a run's steps made of each scan (slam_run.hpp's ScanRecorder).
using BatchRecorder = ScanRecorder;

/// The problem of a run: its inputs (`src`, rewound and read to the end, then rewound), what the
/// steps made of its scans (`rec`, matched by scan time), and the filter's trace
/// (RunOptions::record_trace: the pose after every input, in order) for the start. by_labels: the
/// landmarks are the observations' truths (clutter left out) instead of the ids the steps gave.
/// Throws std::runtime_error when the trace is not one pose per input.
BatchProblem batch_problem(RunSource& src, const BatchRecorder& rec, const std::vector<TracePoint>& trace,
                           const Mount<double>& mount, bool by_labels);

/// Solves the problem (Ceres, sparse normal Cholesky). Throws std::invalid_argument for an empty
/// problem.
BatchResult solve_batch(const BatchProblem& p, const BatchOptions& o);

/// A run's batch references, each started from its trace: the mean position error [m] of the trace
/// at the scans (the filter's, or with local maps on the solver the joined map's smoothed one), of the
/// batch with the run's own pairings (with local maps: the ids the local maps gave, not the joins'
/// fusions) and of the batch with the labels (the true association). NaN where no pose has a truth.
std::array<double, 3> batch_errors(RunSource& src, const BatchRecorder& rec, const RunResult& r, const RunOptions& ro);

/// The mean position error [m] over the poses with a true pose of `poses` (one per scan of p), or
/// NaN when none has one.
double mean_position_error(const BatchProblem& p, const std::vector<Pose2<double>>& poses);

}  // namespace geojcbb::host
