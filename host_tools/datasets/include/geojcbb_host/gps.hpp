// host_tools/datasets: scoring a run without a true pose against GPS (a real vehicle's log, e.g.
// Victoria Park). Fixes are screened first (a receiver that reacquires after a dropout, or jumps,
// gives fixes that are off by metres): a fix more than max_gap_s after the previous fix, or more
// than max_jump_m from it, is rejected. Each kept fix is compared with the estimated antenna
// position at its time: the run's trace (RunResult::trace) interpolated between the two estimates
// around the fix, when they are at most max_dt_s apart; the antenna sits at (antenna_x_m,
// antenna_y_m) in the robot's frame.
#pragma once

#include <vector>

#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host {

struct GpsOptions {
  double max_gap_s = 5.0;    ///< a fix after a longer dropout is rejected
  double max_jump_m = 10.0;  ///< a fix farther than this from the previous fix is rejected
  double max_dt_s = 0.1;     ///< the trace's estimates around a fix must be at most this apart
  double antenna_x_m = 0, antenna_y_m = 0;
};

struct GpsScore {
  int fixes = 0;          ///< given
  int after_gap = 0;      ///< rejected: more than max_gap_s after the previous fix
  int jumps = 0;          ///< rejected: more than max_jump_m from the previous fix
  int unmatched = 0;      ///< kept, but no estimate around its time
  int used = 0;           ///< compared
  double rmse_m = 0;      ///< over the used fixes (NaN when none)
  double max_m = 0;       ///< largest error
  double max_at_s = 0;    ///< its time
  std::vector<double> t;  ///< per used fix: time and error, for figures
  std::vector<double> error_m;
};

/// Where the antenna is when the robot is at x.
Eigen::Vector2d antenna_at(const Pose2<double>& x, const GpsOptions& o);

/// The fixes kept by the screening (in order), with the counts of those rejected.
std::vector<replay::GpsEvent> screen_gps(const std::vector<replay::GpsEvent>& fixes, const GpsOptions& o,
                                         GpsScore& counts);
/// The estimated antenna track against the screened fixes. `trace` in time order.
GpsScore score_gps(const std::vector<TracePoint>& trace, const std::vector<replay::GpsEvent>& fixes,
                   const GpsOptions& o);

}  // namespace geojcbb::host
