// geojcbb_link: streams a simulated scenario through a device over a serial link and scores what
// comes back (the evaluation's TP/TN/FP/FN and pose error). Without --port it starts
// geojcbb_device --pty beside itself, reads the pty's path and connects (the desktop loop), and at
// the end shuts it down with SHUTDOWN. The link reconnects and restarts runs as LinkSession does.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/link_cli.hpp"
#include "geojcbb_host/run_cli.hpp"
#include "geojcbb_host/stream.hpp"
#include "geojcbb_host/guarded_main.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

int run(int argc, char** argv) {
  CLI::App app{"geojcbb_link: stream a simulated scenario through a device over a serial link and score the replies"};
  std::string scenario = std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json";
  LinkCli lc;
  lc.device = (std::filesystem::path(argv[0]).parent_path() / "geojcbb_device").string();
  std::vector<std::string> names;
  std::uint64_t seed = 1;
  RunOptions o;
  add_link_options(app, lc, "device's serial port or pty (default: start --device with --pty)",
                   "device program started when --port is not given");
  add_run_options(app, o);
  bool list_only = false;
  app.add_flag("--list-ports", list_only, "print the serial ports libserialport finds and exit");
  app.add_option("--scenario", scenario, "scenario JSON file")->default_val(scenario);
  app.add_option("--strategies", names,
                 std::string("strategies, comma separated (") + kPresetsHelp +
                     "; default: the papers' six, PCJCBB and the robust preset PCJCBB+RL)")
      ->delimiter(',');
  app.add_option("--seed", seed, "simulation seed")->default_val(seed);
  app.add_option("--max-steps", o.max_steps, "control intervals to stream (0: the whole path)")->default_val(0);
  CLI11_PARSE(app, argc, argv);
  if (list_only) {
    try {
      for (const PortInfo& i : list_ports()) std::printf("%s\n", port_line(i).c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "geojcbb_link: %s\n", e.what());
      return 1;
    }
    return 0;
  }
  int rc = 0;
  try {
    const Scenario sc = load_scenario(scenario);
    DeviceLink dl(lc, lc.port.empty());
    std::printf("%s\n", dl.describe().c_str());
    const std::vector<Method> methods = select_methods(names, true);
    std::printf("%s, seed %llu, streamed over the link, %d scan(s) in flight\n", sc.name.c_str(),
                static_cast<unsigned long long>(seed), lc.window);
    print_score_header();
    StreamOptions so;
    so.window = lc.window;
    so.note = [](const std::string& n) { std::printf("  %s\n", n.c_str()); };
    for (const Method& m : methods) {
      RunOptions ro = o;
      m.apply(ro);
      SimSource src(sc, seed, o.max_steps);
      const auto t0 = std::chrono::steady_clock::now();
      const RunResult r = stream_run(dl.session(), src, ro, so);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      print_score_row(m.name(), r, r.scans / secs);
    }
    std::printf("device STATS: %s\n", describe_stats(dl.session().stats()).c_str());
    if (dl.session().reconnections() > 0) {
      std::printf("link: %d reconnection(s), %d run restart(s)\n", dl.session().reconnections(),
                  dl.session().restarts());
    }
    if (dl.started_device()) {
      const int code = dl.shut_down();
      std::printf("device shut down (SHUTDOWN 0): exit code %d\n", code);
      if (code != 0) rc = 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geojcbb_link: %s\n", e.what());
    rc = 1;
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
