// host_tools/eval: geojcbb_eval's command line. Each subcommand is one file (eval_sim.cpp,
// eval_mrclam.cpp, eval_replay.cpp, eval_convert.cpp) that adds its options and returns what it
// runs (host_tools/suites and host_tools/datasets do the work); eval_main.cpp only registers them
// and runs the one given. The flags the subcommands share (strategies, TRUTH, output folder,
// threads, progress, figures, the device link, the noise) are defined once here, with the run
// options of the table (run_cli.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "geojcbb_host/link_cli.hpp"
#include "geojcbb_host/mrclam_replay.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/suite.hpp"

namespace geojcbb::host {

/// A registered subcommand: its CLI11 app and what runs it after parsing (an exit code).
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Subcommand add_sim_command(CLI::App& app);
Subcommand add_mrclam_command(CLI::App& app);
Subcommand add_replay_command(CLI::App& app);
Subcommand add_convert_mrclam_command(CLI::App& app);
Subcommand add_convert_victoria_command(CLI::App& app);

/// The flags a subcommand that runs presets shares with the others: the suite's (suite.hpp) and
/// the device link's.
struct CommonFlags : SuiteFlags {
  LinkCli link;  ///< --port, --device and the link's options
};

/// Which of CommonFlags a subcommand takes.
enum CommonFlag : unsigned {
  kStrategiesFlag = 1u,
  kTruthFlag = 2u,
  kOutDirFlag = 4u,
  kJobsFlag = 8u,
  kProgressFlag = 16u,
  kSvgFlag = 32u,
  kLinkFlags = 64u,
  kAllCommonFlags = 127u,
};

/// Adds the flags in `which` to `sub`, bound to `f`: `files` names what --out-dir receives, `unit`
/// what one job is ("run", "replay").
void add_common_flags(CLI::App& sub, CommonFlags& f, unsigned which, const std::string& files, const std::string& unit);
/// A progress bar: asked for (no --no-progress) and stderr a terminal.
bool progress_bar(const CommonFlags& f);

/// The four noise flags of a replay (--sigma-range, --sigma-bearing, --sigma-v, --sigma-w; 0: not
/// given) and --noise-inflation, bound to the caller's fields; `where` ends each help text.
struct NoiseFlags {
  double* sigma_range_m;
  double* sigma_bearing_rad;
  double* sigma_v_mps;
  double* sigma_w_radps;
  double* inflation;  ///< null: no --noise-inflation
};
void add_noise_flags(CLI::App& sub, const NoiseFlags& n, const std::string& where);
/// The MRCLAM model's flags (noise, camera, drive, calibration), shared by mrclam and convert-mrclam.
void add_mrclam_model_flags(CLI::App& sub, MrclamOptions& m);

/// Runs `run` in process (no --port/--device: an empty runner), or with every run streamed to the
/// device: prints the device and where its capacity differs from the in-process filter's, and at
/// the end shuts down a device it started. Returns run's exit code (1 when a started device did not
/// exit cleanly). TRUTH and a known map run in process only (refused here).
int with_device(const LinkCli& lc, bool oracle, bool known_map,
                const std::function<int(const RunInputsFn& runner, const std::string& device_info)>& run);

}  // namespace geojcbb::host
