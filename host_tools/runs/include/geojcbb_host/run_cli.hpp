// host_tools: the command-line options of a run, for every program that takes them (geojcbb_eval's
// sim, mrclam and replay, geojcbb_link, geojcbb_qemu): one option per line of the option table
// (core/options.h) that names one, with the table's meaning, unit and range, bound to the run's
// StepSettings; a BOOL gets --name and --no-name. Then the host's own: --compensation (d in r + d)
// and --view-margin. Each option's default is the value the run already holds (MRCLAM's rules, say).
#pragma once

#include <CLI/CLI.hpp>

#include <map>
#include <string>
#include <type_traits>

#include "geojcbb/core/settings.hpp"
#include "geojcbb_host/slam_run.hpp"

namespace geojcbb::host {

inline void add_run_options(CLI::App& app, RunOptions& run) {
  for_each_option(run.step, [&app](const options::Info& info, auto& v) {
    using V = std::remove_reference_t<decltype(v)>;
    if (info.cli[0] == '\0') return;  // set by the host
    std::string what = info.meaning;
    if (info.unit[0] != '\0') what += std::string(" [") + info.unit + "]";
    if constexpr (std::is_same<V, bool>::value) {
      app.add_flag(std::string(info.cli) + ",!--no-" + (info.cli + 2), v, what)->capture_default_str();
    } else if constexpr (!std::is_enum<V>::value) {
      const options::Range range = info.range;
      app.add_option(info.cli, v, what)
          ->capture_default_str()
          ->check(CLI::Validator(
              [range](const std::string& s) {
                try {
                  return range.contains(std::stod(s)) ? std::string() : std::string("outside the option's range");
                } catch (const std::exception&) {
                  return std::string("not a number");
                }
              },
              "", "option table range"));
    }
  });
  app.add_option("--compensation", run.compensation_m, "d in the local region r + d [m] (r: the sensor's max range)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--view-margin", run.view_margin_m,
                 "a landmark within this of the sensor's range limits is not expected in view [m]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag("--submaps", run.submaps,
               "local maps of bounded size, each closed by its rule (--submap-landmarks, --submap-distance, "
               "--submap-scans; none given: at the default device's size less a scan) and joined into one global "
               "map (docs/submaps.md)");
  app.add_flag("--submap-seed", run.submap_seed,
               "with --submaps: before each scan, the global map's landmarks near the robot that the local map does "
               "not hold are seeded into it (docs/submaps.md)");
  app.add_option("--join-preset", run.join_preset, "the association between local maps (docs/submaps.md)")
      ->capture_default_str();
  app.add_option("--join-margin", run.join.margin_d2,
                 "a pairing between maps that a runner-up within this joint d2 makes differently is kept apart")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  app.add_flag("--join-remove-carried", run.join.remove_carried,
               "a landmark a local map was born with (carried over) and removed by its evidence leaves the global "
               "map, as a removed seed does (docs/submaps.md)");
  app.add_option("--join-solver", run.join.solver,
                 "how the global map is held: dense (the EKF-style join, one linearisation) or graph (every local map "
                 "a factor, relinearised by Ceres at each join; docs/mapping.md)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, JoinOptions::Solver>{
          {"dense", JoinOptions::Solver::kDense}, {"graph", JoinOptions::Solver::kGraph}}))
      ->capture_default_str();
  app.add_option("--join-loss", run.join.loss_confidence,
                 "with --join-solver graph: Huber's loss on a local map's factor beyond chi2(this, its dimension); 0: "
                 "none")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.999999));
  app.add_option("--join-window", run.join.solver_window,
                 "with --join-solver graph: a join solves its last N local maps and a prior holding the older ones "
                 "(a map that reaches behind them solves everything); 0: every join solves every map")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000000));
}

}  // namespace geojcbb::host
