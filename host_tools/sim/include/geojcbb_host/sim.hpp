// host_tools/sim: a 2D EKF-SLAM simulator in the spirit of Tim Bailey's (the papers' platform).
// A robot follows a closed waypoint path counter-clockwise at constant speed; odometry reports
// (v, w) with noise; a range-bearing laser sees landmarks within max range and field of view, each
// with a detection probability, plus Poisson clutter. Every run is reproducible from its seed.
// Scenarios are JSON files (host_tools/scenarios/*.json); see docs/simulator.md for the fields.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geojcbb/core/range_bearing.hpp"

namespace geojcbb::host {

struct Scenario {
  std::string name;
  std::vector<Eigen::Vector2d> landmarks;  ///< true positions [m]
  std::vector<Eigen::Vector2d> waypoints;  ///< closed path, driven in order [m]
  int laps = 1;
  /// The path ends after this long even if its laps are not done [s] (0: no limit). The dense scene
  /// uses it: its map outgrows the host's capacity over a whole lap.
  double duration_s = 0;
  double speed_mps = 3.0;            ///< commanded forward speed
  double max_turn_rate_radps = 0.5;  ///< steering saturation
  double turn_gain = 2.0;            ///< w = gain * heading error (saturated)
  double waypoint_radius_m = 1.0;    ///< switch to the next waypoint within this distance
  double dt_s = 0.025;               ///< control interval
  int observe_every = 8;             ///< a scan every this many control intervals (0.2 s)
  double sigma_v_mps = 0.3;          ///< odometry noise (Bailey: speed 0.3 m/s)
  double sigma_w_radps = 0.04;       ///< (Bailey: steering 3 deg on a 4 m wheelbase at 3 m/s)
  double max_range_m = 30.0;
  /// Nearer landmarks are not seen (a laser's blind zone); > 3 sigma_range keeps every simulated
  /// range positive.
  double min_range_m = 1.0;
  double fov_rad = 3.14159265358979;      ///< full field of view (centred ahead)
  double sigma_range_m = 0.1;             ///< (Bailey: 0.1 m)
  double sigma_bearing_rad = 0.01745329;  ///< (Bailey: 1 deg)
  /// Where the sensor sits on the robot (JSON "sensor_mount": {"x_m", "y_m", "theta_deg"}): every
  /// observation is taken from there (core/range_bearing.hpp's Mount); the filter is told.
  double sensor_x_m = 0, sensor_y_m = 0, sensor_theta_rad = 0;
  /// The filter (and a device, as ODOM_DELTA) gets each interval's odometry as the pose increment
  /// the velocity model gives, with its covariance, instead of (v, w) (JSON "odometry_increments").
  bool odometry_increments = false;
  double detection_probability = 1.0;  ///< p_D of every landmark (unless detection_by_beams)
  /// Detection by beams (JSON "detection": {"model": "beams", "beam_deg", "p_by_beams"} and
  /// "landmark_diameters_m"): a landmark of diameter d at range r covers n = 2 atan(d / 2r) / beam
  /// beams of the laser, and is seen with p_by_beams interpolated linearly at n (the last entry from
  /// n = size - 1 on); detection_probability is not used. A tree far away is a beam or two.
  bool detection_by_beams = false;
  double beam_rad = 0.5 * 3.14159265358979 / 180;           ///< angular step of the laser
  std::vector<double> p_by_beams{0.0, 0.2, 0.5, 0.8, 0.9};  ///< p_D at 0, 1, 2, ... beams
  std::vector<double> diameters_m;                          ///< per landmark [m] (detection by beams)
  double clutter_per_scan = 0.0;                            ///< mean of a Poisson count per scan
  /// Multiplies the simulated odometry and measurement noise only; the filter keeps the sigmas
  /// above. 0 gives a noise-free run of a filter that still expects noise.
  double noise_scale = 1.0;
  /// A kidnap (relocalisation scenes, pose-free consistency): at kidnap_t_s the robot is
  /// carried by kidnap_move = (dx [m], dy [m], dtheta [rad]) in the world frame, and the filter's
  /// pose covariance is re-set to diag(kidnap_sigma_xy_m^2, kidnap_sigma_xy_m^2,
  /// kidnap_sigma_theta_rad^2) with the estimate left where it was, as a user would after a reset.
  /// kidnap_t_s <= 0: none.
  double kidnap_t_s = 0;
  Eigen::Vector3d kidnap_move = Eigen::Vector3d::Zero();
  double kidnap_sigma_xy_m = 5.0;
  double kidnap_sigma_theta_rad = 0.5;
  /// false (JSON kidnap "told": false): a silent kidnap, the filter is not told (no reset covariance).
  bool kidnap_told = true;
  /// Bursts of clutter (JSON "clutter_burst": {"t_s", "duration_s", "every_s", "per_scan"}): from
  /// burst_t_s on, for burst_duration_s out of every burst_every_s (0: once), burst_per_scan more
  /// clutter returns per scan (a Poisson mean), all within a 30-degree sector of a bearing drawn per burst.
  double burst_t_s = 0, burst_duration_s = 0, burst_every_s = 0, burst_per_scan = 0;
  /// Landmarks that move (JSON "movers", docs/simulator.md). Out and back ({"index", "vx_mps",
  /// "vy_mps", "period_s"}): landmark `index` goes out along v for half the period and back for the
  /// other half, from t = 0. Walk and stand ({"index", "legs": [[x, y, speed_mps, dwell_s], ...]}, a
  /// person): from the landmark's position it walks to each leg's point at the leg's speed and stands
  /// there for its dwell, leg after leg; after the last it stands. An observation of a mover is not
  /// of a landmark (SimObservation::truth -1, mover its index here).
  struct Mover {
    /// One stretch of a walk: to `to` [m] at speed_mps, then standing for dwell_s.
    struct Leg {
      Eigen::Vector2d to = Eigen::Vector2d::Zero();
      double speed_mps = 1, dwell_s = 0;
    };
    int index = 0;
    Eigen::Vector2d v = Eigen::Vector2d::Zero();
    double period_s = 1;
    std::vector<Leg> legs;  ///< non-empty: walk and stand (v and period_s unused)
  };
  std::vector<Mover> movers;
};

/// Where landmark j of s is at time t (movers move; the rest stand).
Eigen::Vector2d landmark_at(const Scenario& s, std::size_t j, double t_s);

/// The mover (index into s.movers) that landmark j is, or -1 when it stands.
int mover_of(const Scenario& s, std::size_t j);

/// The chance that landmark j of s is seen at range_m: detection_probability, or by its beams.
double detection_probability_at(const Scenario& s, std::size_t j, double range_m);

/// Reads a scenario file. Throws std::runtime_error with the file and field on a bad file.
Scenario load_scenario(const std::string& path);

struct SimObservation {
  Eigen::Vector2d z;  ///< (range [m], bearing [rad])
  int truth;          ///< landmark index, or -1 for clutter and for a mover
  Eigen::Matrix2d R;  ///< the covariance the filter assumes for z (range, bearing)
  int mover = -1;     ///< a mover's observation: its index in Scenario::movers (truth is -1); else -1
};

struct SimStep {
  double t_s = 0;
  Pose2<double> true_pose;
  double v_mps = 0, w_radps = 0;  ///< noisy odometry over the interval that ended here
  bool scan = false;              ///< a scan was taken at the end of this interval
  bool kidnapped = false;         ///< the robot was carried at the start of this interval
  std::vector<SimObservation> observations;
};

class Simulator {
 public:
  Simulator(const Scenario& s, std::uint64_t seed);
  /// Advances one control interval; false once the path's laps are done.
  bool step(SimStep& out);
  const Scenario& scenario() const { return s_; }

 private:
  /// The scan's landmark and mover observations, then its clutter (and bursts).
  void observe_landmarks(SimStep& out, const Eigen::Matrix2d& R);
  void add_clutter(SimStep& out, const Eigen::Matrix2d& R);
  Scenario s_;
  std::mt19937_64 rng_;
  Pose2<double> x_;
  std::size_t target_ = 1;
  int lap_ = 0;
  long k_ = 0;
  bool kidnap_done_ = false;
  std::vector<int> mover_of_;  ///< landmark -> its mover, or -1
  long burst_ = -1;            ///< the burst under way (its index from burst_t_s), -1: none yet
  double burst_bearing_ = 0;   ///< its sector's centre [rad]
};

}  // namespace geojcbb::host
