// geojcbb_eval convert-mrclam and convert-victoria-park: a MRCLAM robot, or ACFR's Victoria Park,
// written as a log of docs/replay.md's format, to be replayed with `replay --log` (the converters:
// log_convert.hpp).
#include <CLI/CLI.hpp>
#include <memory>

#include "geojcbb_host/eval_cli.hpp"
#include "geojcbb_host/log_convert.hpp"

namespace geojcbb::host {

Subcommand add_convert_mrclam_command(CLI::App& app) {
  auto c = std::make_shared<MrclamConvertOptions>();
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
  return {cv, [c]() { return convert_mrclam(*c); }};
}

Subcommand add_convert_victoria_command(CLI::App& app) {
  auto v = std::make_shared<VictoriaConvertOptions>();
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
  return {vp, [v]() { return convert_victoria_park(*v); }};
}

}  // namespace geojcbb::host
