// host_tools/suites: the MRCLAM replay as a whole (docs/mrclam.md): every strategy on every robot
// of every data set (MrclamOptions, mrclam_replay.hpp), reported as the simulation and the own-log
// replay are (report.hpp), with the mover split, the world model, --merge and --batch.
#pragma once

#include <string>

#include "geojcbb_host/mrclam_replay.hpp"

namespace geojcbb::host {

/// Every strategy on every robot of every dataset: tables on stdout, mrclam.csv
/// and mrclam.json in out_dir. Returns the process exit code.
int run_mrclam_report(const MrclamOptions& options, const std::string& out_dir, bool progress);

}  // namespace geojcbb::host
