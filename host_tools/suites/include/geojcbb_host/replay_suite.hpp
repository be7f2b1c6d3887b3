// host_tools/suites: the own-log replay (geojcbb_eval replay, docs/replay.md): every chosen
// strategy on one log, reported as the simulation and the MRCLAM replay are (report.hpp): Tables 1
// and 2 (Table 2 and the summary only when every measurement is labelled), pose and map, the GPS
// score where the log has fixes, the noise from the data or the innovations, the batch reference;
// replay.csv, replay.json, replay_path.svg.
#pragma once

#include <string>

#include "geojcbb_host/batch.hpp"
#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/gps.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/suite.hpp"

namespace geojcbb::host {

struct ReplayOptions {
  std::string log;
  SuiteFlags flags;        ///< --strategies, --truth, --out-dir, --jobs, --no-progress, --no-svg
  replay::LogNoise noise;  ///< 0: from the lines, or from the data
  bool noise_from_data = false;
  bool innovations = false;  ///< --noise-from-innovations
  int innovation_rounds = 6;
  double noise_inflation = 1.5;
  double group_radius_m = 0;  ///< > 0: landmark groups for the group-level score
  bool known_map = false;
  bool write_path = false;  ///< --write-path: path.csv, each strategy's pose after every input; map.csv, its final map
  bool batch = false;       ///< --batch: the batch reference beside each strategy (host_tools/mapping)
  BatchOptions batch_options;
  RunOptions run;
  GpsOptions gps;      ///< the screening (the antenna from the log's meta)
  RunInputsFn runner;  ///< empty: in process; else each replay streamed to a device
};

/// Every strategy on the log: tables on stdout, the files in out_dir. Throws std::runtime_error for a
/// log that cannot be read or options it cannot give (TRUTH without labels, --known-map without
/// landmark lines). Returns the process exit code (1 when a replay failed).
int run_replay(const ReplayOptions& o);

}  // namespace geojcbb::host
