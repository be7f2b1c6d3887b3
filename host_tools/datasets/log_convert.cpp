// host_tools/datasets: a MRCLAM robot, or ACFR's Victoria Park, written as a log of
// docs/replay.md's format (log_convert.hpp).
#include "geojcbb_host/log_convert.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "geojcbb_host/mrclam_calibration.hpp"

namespace geojcbb::host {
namespace fs = std::filesystem;

int convert_mrclam(const MrclamConvertOptions& c) {
  const std::string root = c.data_dir.empty() ? mrclam::default_data_dir() : c.data_dir;
  const mrclam::Dataset ds = mrclam::load_dataset(mrclam::dataset_dir(c.dataset, root));
  const mrclam::RobotLog full = mrclam::load_robot(ds, c.robot);
  const mrclam::RobotLog log = c.seconds > 0 ? replay::truncate(full, c.seconds) : full;
  replay::EventLog out;
  std::string what;
  if (c.raw) {
    out = replay::mrclam_raw_log(ds, log);
    what = "raw: commands and measurements as logged, no noise";
  } else {
    const MrclamOptions& m = c.model;
    MrclamNoise noise = MrclamNoise::from_data(ds, {full}, m.noise_inflation);
    if (m.sigma_range_m > 0) noise.sigma_range_m = m.sigma_range_m;
    if (m.sigma_bearing_rad > 0) noise.sigma_bearing_rad = m.sigma_bearing_rad;
    if (m.sigma_v_mps > 0) noise.sigma_v_mps = m.sigma_v_mps;
    if (m.sigma_w_radps > 0) noise.sigma_w_radps = m.sigma_w_radps;
    mrclam::RobotCalibration cal;
    if (m.camera || m.drive) {
      if (m.calibration == "same") {
        cal = mrclam::calibrate_robot(ds, full, m.calibration_options);
      } else {
        const mrclam::Dataset cds = mrclam::load_dataset(mrclam::dataset_dir(c.dataset == 6 ? 7 : 6, root));
        cal = mrclam::calibrate_robot(cds, mrclam::load_robot(cds, c.robot), m.calibration_options);
      }
    }
    out = replay::mrclam_to_log(ds, log, mrclam_model(noise, cal, m.camera, m.drive, m.model_inflation),
                                m.drop_other_robots);
    what = std::string("the replay's model: camera ") + (m.camera ? "calibrated" : "constant R") + ", drive " +
           (m.drive ? "calibrated (latency, scale, process noise)" : "commands with constant noise") +
           ", calibration " + m.calibration + (m.drop_other_robots ? ", other robots dropped" : "");
  }
  if (fs::path(c.out).has_parent_path()) fs::create_directories(fs::path(c.out).parent_path());
  std::ofstream f(c.out);
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  replay::write_event_log(out, f,
                          "MRCLAM_Dataset" + std::to_string(c.dataset) + " robot " + std::to_string(c.robot) +
                              (c.seconds > 0 ? ", first " + std::to_string(c.seconds) + " s" : std::string()) + "\n" +
                              what);
  f.close();
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  std::printf("%s: %zu odom, %zu meas, %zu empty scans, %zu truth, %zu landmark lines (%s)\n", c.out.c_str(),
              out.odometry.size(), out.measurements.size(), out.empty_scans.size(), out.truth.size(),
              out.landmarks.size(), what.c_str());
  return 0;
}

int convert_victoria_park(const VictoriaConvertOptions& c) {
  const std::string dir = c.data_dir.empty() ? victoria_park::default_data_dir() : c.data_dir;
  const victoria_park::Data data = victoria_park::read(dir);
  const replay::EventLog out = victoria_park::to_log(data, c.model);
  if (fs::path(c.out).has_parent_path()) fs::create_directories(fs::path(c.out).parent_path());
  std::ofstream f(c.out);
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  const victoria_park::ConvertOptions& m = c.model;
  char what[512];
  std::snprintf(what, sizeof what,
                "Victoria Park (ACFR; Guivant and Nebot 2001) from %s\n"
                "reference point: the rear axle's centre; odometry noise per 40 Hz sample: speed %.3g m/s, steering "
                "%.3g rad\ndetections kept: %.3g to %.3g m, |bearing| <= %.3g rad; R = diag(%.3g m, %.3g rad)^2",
                dir.c_str(), m.sigma_speed_mps, m.sigma_steer_rad, m.min_range_m, m.max_range_m, m.max_bearing_rad,
                m.sigma_range_m, m.sigma_bearing_rad);
  replay::write_event_log(out, f, what);
  f.close();
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  std::printf("%s: %zu odom_delta, %zu meas, %zu empty scans, %zu gps lines\n", c.out.c_str(), out.increments.size(),
              out.measurements.size(), out.empty_scans.size(), out.gps.size());
  return 0;
}

}  // namespace geojcbb::host
