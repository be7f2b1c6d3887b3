// host_tools/datasets: a robot's own log in one documented format (docs/replay.md), its reader and
// writer, the run inputs it gives the filter (LogSource), the noise estimated from its labelled
// data, and the converter from a MRCLAM robot. One line per event, CSV, the first field the kind:
//   meta,KEY,VALUE                                    sensor, start pose, scan grouping
//   landmark,LABEL,x,y                                known landmark positions [m]
//   odom,t,v,w[,sigma_v,sigma_w]                      command [m/s, rad/s] from t to the next odom
//   odom_delta,t,dx,dy,dtheta[,cxx,cxy,cxt,cyy,cyt,ctt]  pose increment up to t, its covariance
//   meas,t,range,bearing[,label[,sigma_range,sigma_bearing[,rho]]]   [s, m, rad]; rho: full R
//   scan,t                                            a frame that saw nothing
//   truth,t,x,y,theta                                 ground-truth pose [s, m, m, rad]
//   gps,t,x,y                                         a position fix of the antenna [s, m, m]
// Comment lines ('#') and blank lines are skipped anywhere. A malformed line throws
// std::runtime_error "path:line: reason"; nothing is ever read past it.
#pragma once

#include <Eigen/Core>
#include <array>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "geojcbb_host/mrclam.hpp"
#include "geojcbb_host/mrclam_replay.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host::replay {

/// The label that marks a measurement as clutter (not a landmark) when the log has no landmark lines.
inline constexpr const char* kClutterLabel = "clutter";

struct OdomEvent {
  double t, v, w;
  double sigma_v = -1, sigma_w = -1;  ///< std of v and w over the interval to the next odom line (< 0: not given)
};
/// The robot's motion from the previous odom_delta line's time (the first: from the start pose) to
/// t, in its frame at the start of the motion: forward, left, counter-clockwise.
struct OdomDeltaEvent {
  double t, dx, dy, dtheta;
  /// Upper triangle of the covariance of (dx, dy, dtheta): xx, xy, xtheta, yy, ytheta, thetatheta.
  std::array<double, 6> cov{};
  bool has_cov = false;  ///< false: the replay's --sigma-v/--sigma-w give it (LogSource)
  Eigen::Matrix3d covariance() const;
};
struct MeasEvent {
  double t, range, bearing;
  std::string label;                            ///< empty: unlabelled
  double sigma_range = -1, sigma_bearing = -1;  ///< [m], [rad] (< 0: not given)
  double rho = 0;             ///< correlation of the range and bearing errors: R's off-diagonal is rho sigma_r sigma_b
  Eigen::Matrix2d R() const;  ///< from the sigmas and rho (sigmas given)
};
/// A position fix of the GPS antenna (at meta gps_x_m, gps_y_m in the robot's frame).
struct GpsEvent {
  double t, x, y;
};
struct LandmarkEvent {
  std::string label;
  double x, y;
};

/// A log as read (each stream in time order; lines within a stream must not go back in time).
struct EventLog {
  std::map<std::string, double> meta;  ///< see kMetaKeys
  std::vector<LandmarkEvent> landmarks;
  std::vector<OdomEvent> odometry;  ///< a log has odom lines or odom_delta lines, not both
  std::vector<OdomDeltaEvent> increments;
  std::vector<MeasEvent> measurements;
  std::vector<GpsEvent> gps;
  std::vector<double> empty_scans;  ///< times of `scan` lines
  std::vector<mrclam::PoseSample> truth;
  /// Landmark index of a label: the landmark lines' order, else labels in order of first
  /// appearance; -1 for clutter (kClutterLabel, or a label without a landmark line when there are some).
  int truth_index(const std::string& label) const;
  /// truth_index of every landmark label (clutter labels absent).
  std::map<std::string, int> label_indices() const;
  /// Landmark labels in index order.
  std::vector<std::string> landmark_labels() const;
  /// Every measurement carries a label (scores are computed).
  bool labelled() const;
};

/// The meta keys a log may set (any other is an error).
const std::vector<std::string>& meta_keys();

/// Reads a log. `name` names the source in error messages. Throws std::runtime_error.
EventLog read_event_log(std::istream& in, const std::string& name);
EventLog read_event_log(const std::string& path);
/// Writes a log (doubles with 17 significant digits, so it reads back bit for bit).
void write_event_log(const EventLog& log, std::ostream& out, const std::string& comment = "");

/// Noise the filter assumes where a line does not give it: R = diag(sigma_range^2,
/// sigma_bearing^2); the odometry sigmas are rates as in MrclamNoise (over dt: sigma * sqrt(1 s / dt)).
struct LogNoise {
  double sigma_range_m = 0, sigma_bearing_rad = 0, sigma_v_mps = 0, sigma_w_radps = 0;  ///< 0: not given
};

/// Robust spreads (as MrclamNoise::from_data) of the labelled measurements' residuals against the
/// ground truth and the landmark lines, and of the 1-second odometry residuals, x inflation.
/// Throws when the log lacks labels, truth or landmark positions.
LogNoise estimate_noise(const EventLog& log, double inflation);

/// A log as a run's inputs. A command holds from its odom line to the next; before each scan the
/// filter predicts to the scan's time. A line's own sigmas are used as given for its whole interval
/// (a part of length dt of an interval T, split by a scan, gets sigma * sqrt(T / dt)); otherwise
/// `noise`. Measurements within scan_tolerance_s (meta, default 0) of a scan's first one join it.
/// Events before the first odom line are skipped. Pose increments are not split: a scan is taken
/// at the pose of the last odom_delta line at or before it (a converter ends an increment at each
/// scan's time); an increment without its covariance gets diag(sigma_v^2 dt, 0, sigma_w^2 dt) from
/// `noise` (dt since the previous odom_delta line). The sensor's mount comes from meta sensor_x_m,
/// sensor_y_m, sensor_theta_rad. Throws std::runtime_error when the log has no odom or odom_delta
/// line, or a measurement or increment has no noise from its line or `noise`.
class LogSource : public RecordedSource {
 public:
  LogSource(const EventLog& log, const LogNoise& noise);
};

/// A MRCLAM robot as a log of what its replay feeds the filter (MrclamSource): the drive model's
/// commands (latency, scale) and their noise as odom lines, the camera-corrected measurements
/// with their R as meas lines (label: the landmark's subject number, or "clutter" for other
/// robots and unknown barcodes), the ground truth, the surveyed landmarks, the sensor and the
/// start. Its replay by LogSource equals MrclamSource's.
EventLog mrclam_to_log(const mrclam::Dataset& ds, const mrclam::RobotLog& robot, const MrclamModel& model,
                       bool drop_other_robots = false);
/// A MRCLAM robot's raw data as a log: commands, measurements as logged (label: subject number, or
/// "clutter"), truth and landmarks; no noise, no model (the replay estimates or is given the noise).
EventLog mrclam_raw_log(const mrclam::Dataset& ds, const mrclam::RobotLog& robot);

/// The first `seconds` of a robot's log (from its first odometry sample); for short replays.
mrclam::RobotLog truncate(const mrclam::RobotLog& log, double seconds);

/// Landmark index -> group (landmarks within radius_m, connected), for RunOptions::landmark_group.
std::vector<int> landmark_groups(const std::vector<Eigen::Vector2d>& landmarks, double radius_m);
/// The log's landmark positions in index order (empty without landmark lines).
std::vector<Eigen::Vector2d> landmark_positions(const EventLog& log);

}  // namespace geojcbb::host::replay
