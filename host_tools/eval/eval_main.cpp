// geojcbb_eval: the evaluation that reproduces the papers' tables and figures, one subcommand per
// file (eval_cli.hpp):
//   sim                    Monte Carlo EKF-SLAM runs over simulated scenarios (eval_sim.cpp)
//   mrclam                 the same filter and metrics on the UTIAS MRCLAM real data (eval_mrclam.cpp)
//   replay                 the same on a user's own log, docs/replay.md (eval_replay.cpp)
//   convert-mrclam         a MRCLAM robot written as such a log (eval_convert.cpp)
//   convert-victoria-park  ACFR's Victoria Park written as such a log (eval_convert.cpp)
// All report through report.hpp (tables, CSV, JSON, figures). With --port (or --device, which starts
// a device program on a pty) every run is streamed to a device over the serial link instead of
// running in process (host_tools/link: stream_run), and the device's replies are scored the same
// way. Timing never decides anything here; it is reported.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <vector>

#include "geojcbb_host/eval_cli.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {

int run(int argc, char** argv) {
  using namespace geojcbb::host;
  CLI::App app{
      "geojcbb evaluation: EKF-SLAM with every association strategy, scored against ground truth, on simulated "
      "scenarios (sim), the UTIAS MRCLAM real data (mrclam) or your own log (replay; convert-mrclam and "
      "convert-victoria-park write such logs)."};
  app.require_subcommand(1);
  const std::vector<Subcommand> commands{add_sim_command(app), add_mrclam_command(app), add_replay_command(app),
                                         add_convert_mrclam_command(app), add_convert_victoria_command(app)};
  CLI11_PARSE(app, argc, argv);
  try {
    for (const Subcommand& c : commands) {
      if (c.app->parsed()) return c.run();
    }
    return 2;  // require_subcommand(1): not reached
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geojcbb_eval: %s\n", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
