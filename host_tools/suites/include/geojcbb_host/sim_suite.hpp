// host_tools/suites: the simulation (geojcbb_eval sim): Monte Carlo EKF-SLAM runs over simulated
// scenarios (every strategy on the same seeds), and over generated worlds: Table 1 (association
// time), Table 2 (TP/TN/FP/FN, precision, recall, F1, accuracy), x/y pose error, NEES with its 95 %
// bounds; runs.csv, summary.json and SVG figures (path fitting, x/y error over time, F1 per
// strategy, NEES over time); the worlds' tables and the batch reference when asked.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/suite.hpp"

namespace geojcbb::host {

struct SimOptions {
  std::vector<std::string> scenarios;
  int runs = 20;
  std::uint64_t seed = 1;
  SuiteFlags flags;  ///< --strategies, --truth, --out-dir, --jobs, --no-progress, --no-svg
  RunOptions run;
  RunInputsFn runner;       ///< empty: in process
  std::string device_info;  ///< the device the runs were streamed to (empty: in process)
  // Generated worlds (--worlds): drawn, written as scenario files and run like --scenario files.
  int worlds = 0;
  int world_runs = 1;  ///< runs per world: 1, or --runs when given
  std::uint64_t world_seed = 1000;
  std::string family;                     ///< empty: the families in turn
  std::vector<std::string> world_family;  ///< per scenario: its family ("" for a --scenario file)
  bool batch = false;                     ///< --batch: the batch reference beside each run (host_tools/mapping)
};

/// The generated worlds (o.worlds of them, world k from o.world_seed + k, of o.family or the
/// families in turn) drawn, written to out_dir/worlds/FAMILY_SEED.json and added to o.scenarios, with
/// o.world_family set for every scenario ("" for a --scenario file).
void add_generated_worlds(SimOptions& o);

/// Every strategy on every scenario: tables on stdout, runs.csv, summary.json and the figures in
/// out_dir. Returns the process exit code (1 when a run failed).
int run_sim(const SimOptions& o);

}  // namespace geojcbb::host
