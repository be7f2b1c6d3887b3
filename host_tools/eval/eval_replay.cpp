// geojcbb_eval replay: every chosen strategy on one log of the user's own (docs/replay.md); the
// replays and their report are replay_suite.hpp's.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "geojcbb_host/eval_cli.hpp"
#include "geojcbb_host/mrclam_replay.hpp"
#include "geojcbb_host/replay_suite.hpp"
#include "geojcbb_host/run_cli.hpp"

namespace geojcbb::host {

Subcommand add_replay_command(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  auto flags = std::make_shared<CommonFlags>();
  flags->out_dir = "build/results/replay";
  CLI::App* rp =
      app.add_subcommand("replay",
                         "replay your own log (docs/replay.md): every strategy, scored when the measurements "
                         "are labelled; tables, replay.csv, replay.json and the path/map figure");
  rp->add_option("--log", o->log, "the log file (CSV, docs/replay.md)")->required();
  add_common_flags(*rp, *flags, kAllCommonFlags, "replay.csv, replay.json and replay_path.svg", "replay");
  add_noise_flags(*rp,
                  {&o->noise.sigma_range_m, &o->noise.sigma_bearing_rad, &o->noise.sigma_v_mps, &o->noise.sigma_w_radps,
                   &o->noise_inflation},
                  " where a line gives none");
  rp->add_flag("--noise-from-data", o->noise_from_data,
               "estimate the noise from the labelled measurements, truth and landmark lines (robust spreads; a "
               "--sigma-* given overrides its part)");
  rp->add_flag("--noise-from-innovations", o->innovations,
               "for a log without labels or truth: R (range, bearing) and the odometry noise scaled so that the pairs' "
               "innovations match their covariance, in rounds of replays with the first strategy (docs/replay.md); "
               "from the noise the log and the --sigma-* give (else 0.1 m, 0.05 rad, 0.1 m/s, 0.1 rad/s)");
  rp->add_option("--innovation-rounds", o->innovation_rounds, "--noise-from-innovations: replays, each one round")
      ->default_val(o->innovation_rounds)
      ->check(CLI::Range(1, 50));
  rp->add_option("--group-radius", o->group_radius_m,
                 "landmarks within this distance [m] form a group, for a group-level score (0: none)")
      ->default_val(0.0)
      ->check(CLI::Range(0.0, 1000.0));
  rp->add_flag("--known-map", o->known_map, "localisation only: the landmark lines are the map (std 1 cm, fixed)");
  rp->add_flag("--write-path", o->write_path,
               "path.csv: each strategy's pose estimate after every prediction and scan, and map.csv: its final "
               "map's landmarks (with --submaps, the global map, in the global frame)");
  rp->add_flag("--batch", o->batch,
               "the batch reference: every pose and landmark solved at once (Ceres) with each strategy's pairings, "
               "and with the labels where the log has them, its GPS RMSE beside the filter's (batch.csv)");
  rp->add_option("--batch-huber", o->batch_options.huber,
                 "--batch: Huber's threshold on an observation's whitened residual [sigma] (0: plain least squares)")
      ->default_val(o->batch_options.huber)
      ->check(CLI::Range(0.0, 100.0));
  auto mrclam_rules = std::make_shared<bool>(false);
  rp->add_flag("--mrclam-rules", *mrclam_rules,
               "the MRCLAM replay's landmark rules (miss probability 1e-5, static gate 0.95, new if taken, occlusion "
               "0.03 rad) where not given");
  rp->add_option("--gps-max-gap", o->gps.max_gap_s, "a GPS fix after a longer dropout is not scored [s]")
      ->default_val(o->gps.max_gap_s)
      ->check(CLI::Range(0.0, 1e6));
  rp->add_option("--gps-max-jump", o->gps.max_jump_m, "a GPS fix farther from the previous one is not scored [m]")
      ->default_val(o->gps.max_jump_m)
      ->check(CLI::Range(0.0, 1e6));
  add_run_options(*rp, o->run);
  return {rp, [o, flags, mrclam_rules, rp]() {
            if (*mrclam_rules) {
              const RunOptions m = mrclam_run_defaults();
              if (rp->count("--static-gate-level") == 0) o->run.step.static_gate_level = m.step.static_gate_level;
              if (rp->count("--reserve-nats") == 0) o->run.step.landmark_reserve_nats = m.step.landmark_reserve_nats;
              if (rp->count("--new-if-taken") == 0)
                o->run.step.new_if_candidates_taken = m.step.new_if_candidates_taken;
              if (rp->count("--occlusion") == 0) o->run.step.occlusion_rad = m.step.occlusion_rad;
            }
            flags->progress = progress_bar(*flags);
            o->flags = *flags;  // the link's flags stay here: with_device below
            return with_device(flags->link, flags->oracle, o->known_map,
                               [&](const RunInputsFn& runner, const std::string&) {
                                 o->runner = runner;
                                 return run_replay(*o);
                               });
          }};
}

}  // namespace geojcbb::host
