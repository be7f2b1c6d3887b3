// geojcbb_eval mrclam: the UTIAS MRCLAM data sets replayed with every strategy on every robot,
// scored with the barcodes' ground truth (mrclam_replay.hpp, docs/mrclam.md).
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "geojcbb_host/batch.hpp"
#include "geojcbb_host/eval_cli.hpp"
#include "geojcbb_host/mrclam_suite.hpp"
#include "geojcbb_host/run_cli.hpp"

namespace geojcbb::host {

void add_mrclam_model_flags(CLI::App& sub, MrclamOptions& m) {
  add_noise_flags(sub, {&m.sigma_range_m, &m.sigma_bearing_rad, &m.sigma_v_mps, &m.sigma_w_radps, &m.noise_inflation},
                  " (default: from the data, see docs/mrclam.md)");
  sub.add_flag("!--no-camera", m.camera,
               "do not use the calibrated camera (range and bearing bias, range-proportional R)");
  sub.add_flag("!--no-drive", m.drive,
               "do not use the calibrated drive (command latency and scale, motion-dependent process noise)");
  sub.add_option("--calibration", m.calibration,
                 "fit each robot's camera and drive on: cross (the same robot in the other dataset) or same")
      ->default_val(m.calibration)
      ->check(CLI::IsMember({"cross", "same"}));
  sub.add_option("--model-inflation", m.model_inflation, "factor on the calibrated standard deviations")
      ->default_val(m.model_inflation)
      ->check(CLI::Range(0.1, 100.0));
  sub.add_flag("--drop-other-robots", m.drop_other_robots,
               "remove measurements of the other robots instead of feeding them as clutter");
}

Subcommand add_mrclam_command(CLI::App& app) {
  struct Options {
    MrclamOptions m;
    CommonFlags flags;
    bool legacy = false;
  };
  auto o = std::make_shared<Options>();
  o->flags.out_dir = "build/results/mrclam";
  CLI::App* mr = app.add_subcommand("mrclam",
                                    "replay the UTIAS MRCLAM datasets: every strategy on every robot, scored with the "
                                    "barcodes' ground truth");
  MrclamOptions& m = o->m;
  mr->add_option("--data", m.data_dir,
                 "folder holding MRCLAM_Dataset6 and MRCLAM_Dataset7 (default: $GEOJCBB_MRCLAM_DIR, else "
                 "../shared/data/mrclam beside the repository)");
  mr->add_option("--datasets", m.datasets, "dataset numbers")->delimiter(',')->default_str("6,7");
  mr->add_option("--robots", m.robots, "robot numbers")->delimiter(',')->default_str("1,2,3,4,5");
  add_common_flags(*mr, o->flags, kAllCommonFlags & ~kSvgFlag, "mrclam.csv and mrclam.json", "replay");
  add_mrclam_model_flags(*mr, m);
  mr->add_flag("--known-map", m.known_map,
               "localisation only: the surveyed landmark positions are the map from the start (std 1 cm), nothing "
               "is added or removed; separates association from mapping");
  mr->add_option("--trace", m.trace_dir,
                 "write one CSV per replay into this folder: per scan the pose error, variances, NEES, pairings, NIS");
  mr->add_flag("--legacy-model", o->legacy,
               "the constant noise model of before (no calibration): R and the odometry noise from --sigma-* or "
               "the data's robust spreads x --noise-inflation; the same as --no-camera --no-drive");
  mr->add_option("--fit-window", m.calibration_options.fit_window_s,
                 "window over which the drive's scale and noise are fitted [s]")
      ->default_val(m.calibration_options.fit_window_s)
      ->check(CLI::Range(0.1, 30.0));
  mr->add_flag("--merge", m.merge,
               "per data set and strategy, merge the robots' final maps into one global map with their start poses "
               "unknown (a pose-free alignment finds them; docs/submaps.md): prints the global map, wrong joins and "
               "the starts found against the ground truth");
  mr->add_option("--seconds", m.seconds,
                 "only each robot's first seconds, from its first odometry sample (0: all); with --merge, the maps "
                 "as they were then")
      ->default_val(m.seconds)
      ->check(CLI::NonNegativeNumber);
  auto batch = std::make_shared<bool>(false);
  mr->add_flag("--batch", *batch,
               "the batch reference: each replay's poses and landmarks solved at once (Ceres) with its own pairings "
               "and with the labels, their mean position error beside the replay's (docs/mapping.md)");
  add_run_options(*mr, m.run);
  return {mr, [o, batch]() {
            MrclamOptions& mo = o->m;
            mo.strategies = select_methods(o->flags.strategies, true, o->flags.oracle);
            mo.jobs = o->flags.jobs;
            if (o->legacy) mo.camera = mo.drive = false;
            if (*batch) {
              if (!o->flags.link.port.empty() || !o->flags.link.device.empty())
                throw std::invalid_argument("--batch: in process only (a device does not report its pairings)");
              mo.batch = batch_errors;
            }
            return with_device(o->flags.link, o->flags.oracle, mo.known_map,
                               [&](const RunInputsFn& runner, const std::string&) {
                                 mo.runner = runner;
                                 if (runner) mo.jobs = 1;  // one device, one replay at a time
                                 return run_mrclam_report(mo, o->flags.out_dir, progress_bar(o->flags));
                               });
          }};
}

}  // namespace geojcbb::host
