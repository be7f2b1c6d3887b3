// host_tools/datasets: ACFR's Victoria Park (Guivant and Nebot 2001) as a log of docs/replay.md's
// format. The data (README.md, "Data"): odometry at 40 Hz (the rear left wheel's speed and the
// steering angle), the tree detections of ACFR's detector per laser frame, GPS. No labels: a
// replay is scored by GPS, the landmarks mapped and the NIS.
//
// The reference point is the centre of the rear axle, where the Ackermann model is exactly a
// unicycle: v_c = v_e / (1 - tan(steer) H / L) (the encoder wheel H = 0.76 m left of the
// centreline), w = v_c tan(steer) / L (wheelbase L = 2.83 m). Each odometry sample's command holds
// to the next sample; its interval (split at each laser frame's time, so a scan sees the pose at
// its time) becomes a pose increment along the arc, with the covariance J diag(sigma_v^2,
// sigma_steer^2) J^T of the speed and steering noise (a part of length dt of a sample of length
// T: the sigmas times sqrt(T / dt), so the sample's total is unchanged). The laser (and the GPS
// antenna) sit 3.78 m ahead of the rear axle and 0.50 m to its left: the sensor mount.
#pragma once

#include <string>
#include <vector>

#include "geojcbb/ekf/motion.hpp"
#include "geojcbb_host/event_log.hpp"

namespace geojcbb::host::victoria_park {

/// $GEOJCBB_VICTORIA_PARK_DIR, else ../shared/data/victoria_park beside the repository.
std::string default_data_dir();

struct OdometrySample {
  double t, speed_mps, steer_rad;
};
struct Frame {
  double t;
  std::vector<double> range_m, bearing_rad;  ///< bearing: 0 ahead, positive to the left
};
struct Data {
  std::vector<OdometrySample> odometry;
  std::vector<Frame> frames;  ///< every laser frame, those without detections too
  std::vector<replay::GpsEvent> gps;
};
/// Reads odometry.csv, laser_frames.csv, tree_detections.csv and gps.csv from `dir`. Throws
/// std::runtime_error "path:line: reason".
Data read(const std::string& dir);

struct Vehicle {
  double wheelbase_m = 2.83;       ///< L
  double encoder_offset_m = 0.76;  ///< H: the encoder wheel to the left of the centreline
  double laser_x_m = 3.78;         ///< the laser (and GPS antenna) ahead of the rear axle
  double laser_y_m = 0.50;         ///< ... and to the left of the centreline
};

struct ConvertOptions {
  Vehicle vehicle;
  double sigma_speed_mps = 1.0;        ///< per odometry sample (PHD-SLAM 3.0's setting)
  double sigma_steer_rad = 0.0698;     ///< 4 degrees, per sample
  double sigma_range_m = 1.0;          ///< R of every detection
  double sigma_bearing_rad = 0.01745;  ///< 1 degree
  double min_range_m = 1.0;            ///< detections kept within [min, max] and |bearing| <= max
  double max_range_m = 50.0;
  double max_bearing_rad = 1.4835;  ///< 85 degrees
  /// The usual start: the laser at the first GPS fix, the heading set by hand.
  double start_laser_x_m = -67.6493, start_laser_y_m = -41.7142, start_theta_rad = 0.61959;  ///< 35.5 degrees
  double start_var = 1e-6;  ///< of x, y, theta at the start
  double seconds = 0;       ///< > 0: only the first seconds of odometry
};

/// One sample's command over dt as an increment of the rear axle's centre, with its covariance.
ekf::PoseIncrement<double> ackermann_increment(double speed_mps, double steer_rad, double dt_s, double sigma_speed_mps,
                                               double sigma_steer_rad, const Vehicle& v);

/// The data as a log: odom_delta lines, meas lines with sigmas, scan lines for frames with nothing
/// kept, gps lines, and meta (sensor limits, mount, GPS antenna, start pose).
replay::EventLog to_log(const Data& data, const ConvertOptions& o);

}  // namespace geojcbb::host::victoria_park
