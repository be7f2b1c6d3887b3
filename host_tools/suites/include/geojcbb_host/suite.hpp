// host_tools/suites: what every suite (the simulation, the own-log replay, the MRCLAM replay) is
// told besides its own options: the strategies, the TRUTH row, where its files go, the threads,
// the progress bar and the figures. geojcbb_eval's CommonFlags (eval_cli.hpp) are these and the
// device link.
#pragma once

#include <string>
#include <vector>

namespace geojcbb::host {

struct SuiteFlags {
  std::vector<std::string> strategies;  ///< --strategies (empty: the six papers' presets, PCJCBB and PCJCBB+RL)
  bool oracle = false;                  ///< --truth
  std::string out_dir;                  ///< --out-dir (its default: the value held)
  int jobs = 0;                         ///< --jobs (0: the number of cores)
  bool progress = true;                 ///< --no-progress clears it (and a stderr that is no terminal)
  bool svg = true;                      ///< --no-svg clears it
};

}  // namespace geojcbb::host
