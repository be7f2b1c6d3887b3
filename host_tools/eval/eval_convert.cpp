// geojcbb_eval convert-mrclam and convert-victoria-park: a MRCLAM robot, or ACFR's Victoria Park,
// written as a log of docs/replay.md's format, to be replayed with `replay --log`.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "geojcbb_host/eval_cli.hpp"
#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/gps.hpp"
#include "geojcbb_host/mrclam_replay.hpp"
#include "geojcbb_host/report.hpp"
#include "geojcbb_host/run_cli.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/svg_plot.hpp"
#include "geojcbb_host/victoria_park.hpp"

namespace geojcbb::host {
namespace fs = std::filesystem;

namespace {

// A MRCLAM robot as a log (docs/replay.md): with its model (what MrclamSource feeds the filter,
// as `geojcbb_eval mrclam --datasets D --robots R` builds it) or raw.
struct ConvertOptions {
  std::string data_dir, out;
  int dataset = 6, robot = 1;
  double seconds = 0;  ///< > 0: only the first seconds
  bool raw = false;
  MrclamOptions model;  ///< the model switches, as for `mrclam`
};

int run_convert(const ConvertOptions& c) {
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

// Victoria Park as a log (docs/victoria_park.md): the rear axle's increments, the laser's mount,
// the detections kept, GPS.
struct VictoriaOptions {
  std::string data_dir, out;
  victoria_park::ConvertOptions model;
};

int run_convert_victoria(const VictoriaOptions& c) {
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
}  // namespace

Subcommand add_convert_mrclam_command(CLI::App& app) {
  auto c = std::make_shared<ConvertOptions>();
  CLI::App* cv = app.add_subcommand("convert-mrclam",
                                    "write a MRCLAM robot as a log of docs/replay.md's format: with the replay's model "
                                    "(replays to the same results as `mrclam --datasets D --robots R`) or --raw");
  cv->add_option("--data", c->data_dir, "folder holding MRCLAM_Dataset6 and 7 (default as for mrclam)");
  cv->add_option("--dataset", c->dataset, "dataset number")->default_val(6)->check(CLI::IsMember({6, 7}));
  cv->add_option("--robot", c->robot, "robot number")->default_val(1)->check(CLI::Range(1, 5));
  cv->add_option("--out", c->out, "the log file to write")->required();
  cv->add_option("--seconds", c->seconds, "only the first seconds of the robot's log (0: all)")
      ->default_val(0.0)
      ->check(CLI::Range(0.0, 1e6));
  cv->add_flag("--raw", c->raw,
               "the data as logged (commands, measurements, labels, truth, landmarks), no model or noise: replay "
               "it with --noise-from-data or --sigma-*");
  add_mrclam_model_flags(*cv, c->model);
  return {cv, [c]() { return run_convert(*c); }};
}

Subcommand add_convert_victoria_command(CLI::App& app) {
  auto v = std::make_shared<VictoriaOptions>();
  CLI::App* vp = app.add_subcommand("convert-victoria-park",
                                    "write ACFR's Victoria Park as a log of docs/replay.md's format "
                                    "(docs/victoria_park.md): pose increments of the rear axle, the laser's mount, "
                                    "detections, GPS; replay it with `replay --log`");
  victoria_park::ConvertOptions& m = v->model;
  vp->add_option("--data", v->data_dir,
                 "the folder of the four CSV files (default $GEOJCBB_VICTORIA_PARK_DIR, else "
                 "../shared/data/victoria_park beside the repository)");
  vp->add_option("--out", v->out, "the log file to write")->required();
  vp->add_option("--sigma-speed", m.sigma_speed_mps, "speed noise per 40 Hz odometry sample [m/s]")
      ->default_val(m.sigma_speed_mps)
      ->check(CLI::Range(0.0, 100.0));
  vp->add_option("--sigma-steer", m.sigma_steer_rad, "steering noise per sample [rad]")
      ->default_val(m.sigma_steer_rad)
      ->check(CLI::Range(0.0, 1.0));
  vp->add_option("--sigma-range", m.sigma_range_m, "range noise of a detection [m]")
      ->default_val(m.sigma_range_m)
      ->check(CLI::Range(1e-6, 100.0));
  vp->add_option("--sigma-bearing", m.sigma_bearing_rad, "bearing noise of a detection [rad]")
      ->default_val(m.sigma_bearing_rad)
      ->check(CLI::Range(1e-6, 1.0));
  vp->add_option("--min-range", m.min_range_m, "detections nearer are dropped [m]")
      ->default_val(m.min_range_m)
      ->check(CLI::Range(0.0, 100.0));
  vp->add_option("--max-range", m.max_range_m, "detections farther are dropped [m]")
      ->default_val(m.max_range_m)
      ->check(CLI::Range(1.0, 100.0));
  vp->add_option("--max-bearing", m.max_bearing_rad, "detections wider are dropped [rad]")
      ->default_val(m.max_bearing_rad)
      ->check(CLI::Range(0.01, 1.5708));
  vp->add_option("--start-theta", m.start_theta_rad, "the start heading [rad]")->default_val(m.start_theta_rad);
  vp->add_option("--seconds", m.seconds, "only the first seconds of the run (0: all)")
      ->default_val(m.seconds)
      ->check(CLI::Range(0.0, 1e6));
  return {vp, [v]() { return run_convert_victoria(*v); }};
}

}  // namespace geojcbb::host
