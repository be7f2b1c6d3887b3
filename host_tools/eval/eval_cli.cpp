// host_tools/eval: the flags geojcbb_eval's subcommands share, and the device a run may be streamed
// to (eval_cli.hpp).
#include "geojcbb_host/eval_cli.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>

#include "geojcbb_host/link.hpp"
#include "geojcbb_host/stream.hpp"

namespace geojcbb::host {

void add_common_flags(CLI::App& sub, CommonFlags& f, unsigned which, const std::string& files,
                      const std::string& unit) {
  if ((which & kStrategiesFlag) != 0) {
    sub.add_option("--strategies", f.strategies,
                   std::string("strategies, comma separated (") + kPresetsHelp +
                       "; default the six papers' presets, PCJCBB and the robust preset PCJCBB+RL)")
        ->delimiter(',');
  }
  if ((which & kTruthFlag) != 0) {
    sub.add_flag("--truth", f.oracle,
                 "add a row TRUTH: association by ground truth (the labels; gated at chi2(0.999, 2)), the filter's "
                 "own accuracy with perfect association");
  }
  if ((which & kOutDirFlag) != 0)
    sub.add_option("--out-dir", f.out_dir, "directory for " + files)->default_val(f.out_dir);
  if ((which & kJobsFlag) != 0) {
    sub.add_option("--jobs", f.jobs, "worker threads (default: the number of cores; 1 gives the cleanest timing)")
        ->check(CLI::Range(0, 256));
  }
  if ((which & kProgressFlag) != 0) sub.add_flag("!--no-progress", f.progress, "no progress bar on stderr");
  if ((which & kSvgFlag) != 0) sub.add_flag("!--no-svg", f.svg, "do not write the figures");
  if ((which & kLinkFlags) != 0) {
    add_link_options(
        sub, f.link,
        "stream every " + unit +
            " to the device on this serial port or pty instead of running it in "
            "process (settings the device cannot run are refused)",
        ("start this device program with --pty (e.g. geojcbb_device) and stream every " + unit + " to it").c_str());
  }
}

bool progress_bar(const CommonFlags& f) { return f.progress && isatty(STDERR_FILENO) != 0; }

void add_noise_flags(CLI::App& sub, const NoiseFlags& n, const std::string& where) {
  sub.add_option("--sigma-range", *n.sigma_range_m, "range std for R [m]" + where);
  sub.add_option("--sigma-bearing", *n.sigma_bearing_rad, "bearing std for R [rad]" + where);
  sub.add_option("--sigma-v", *n.sigma_v_mps, "odometry v noise, std of a 1-second mean [m/s]" + where);
  sub.add_option("--sigma-w", *n.sigma_w_radps, "odometry w noise, std of a 1-second mean [rad/s]" + where);
  if (n.inflation != nullptr) {
    sub.add_option("--noise-inflation", *n.inflation, "factor on the data's robust noise spreads")
        ->default_val(*n.inflation)
        ->check(CLI::Range(0.1, 100.0));
  }
}

int with_device(const LinkCli& lc, bool oracle, bool known_map,
                const std::function<int(const RunInputsFn& runner, const std::string& device_info)>& run) {
  if (lc.port.empty() && lc.device.empty()) return run(RunInputsFn{}, std::string{});
  if (!lc.port.empty() && !lc.device.empty()) throw std::runtime_error("give --port or --device, not both");
  if (oracle) throw std::runtime_error("the TRUTH row (--truth) runs in process only: drop it with --port/--device");
  if (known_map) {  // link_config refuses it too, per run; here before a device is started
    throw std::runtime_error(
        "known_map (--known-map): CONFIG carries no landmarks, so a device would map instead of localise; run it in "
        "process");
  }
  DeviceLink dl(lc, !lc.device.empty());
  const std::string info = dl.describe();
  std::printf("%s; %d scan(s) in flight, reply timeout %d ms\n", info.c_str(), lc.window, lc.timeout_ms);
  const proto::Capabilities& caps = dl.session().capabilities();
  const int obs = std::min<int>(caps.max_observations, static_cast<int>(kLinkMaxObs));
  if (obs < kEvalMaxObservations) {
    std::printf(
        "  the device takes at most %d observations per scan (in process: %d): each scan's nearest %d are "
        "sent, the rest dropped and not scored\n",
        obs, kEvalMaxObservations, obs);
  }
  if (caps.max_landmarks < kEvalMaxLandmarks) {
    std::printf(
        "  the device's map holds %u landmarks (in process: %d): past that, new landmarks are not added "
        "(noted per run)\n",
        caps.max_landmarks, kEvalMaxLandmarks);
  }
  std::mutex mu;
  std::set<std::string> said;
  StreamOptions st;
  st.window = lc.window;
  st.note = [&](const std::string& n) {
    std::lock_guard<std::mutex> lock(mu);
    if (said.insert(n).second) std::printf("  %s\n", n.c_str());
  };
  const RunInputsFn runner = [&](RunSource& src, const RunOptions& ro) {
    return stream_run(dl.session(), src, ro, st);
  };
  int rc = run(runner, info);
  if (dl.session().reconnections() > 0) {
    std::printf("link: %d reconnection(s), %d run restart(s)\n", dl.session().reconnections(), dl.session().restarts());
  }
  if (dl.started_device()) {
    const int code = dl.shut_down();
    if (code != 0) {
      std::fprintf(stderr, "geojcbb_eval: the device did not exit cleanly after SHUTDOWN (exit code %d)\n", code);
      if (rc == 0) rc = 1;
    }
  }
  return rc;
}

}  // namespace geojcbb::host
