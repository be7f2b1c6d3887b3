// link_bench: end-to-end scans per second over the serial link (a pty to geojcbb_device by default),
// and where the time goes. For each strategy, on the same recorded scans (the simulator runs before
// the clock starts):
//   in-process  the device's own work, in this process: node::SlamStep<float, DesktopBounds> fed with
//               the same decoded messages (ODOMETRY -> predict, OBS_BATCH -> step): the baseline
//   link, w=W   stream_run over the link with W batches in flight (ODOMETRY + OBS_BATCH sent ahead,
//               replies matched by batch id), scored as the evaluation scores; the ratio is against
//               the in-process rate of the same run
// and the round trip of a PING over the same link. The results of every window must be the same
// (the device processes in order); the program says so, or fails. Timing is reported, never asserted.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb/node/node.hpp"
#include "geojcbb_host/link_cli.hpp"
#include "geojcbb_host/stream.hpp"
#include "geojcbb_host/guarded_main.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// One run's inputs as the device receives them.
struct Messages {
  proto::Config config;
  proto::Reset reset;
  std::vector<bool> is_scan;
  std::vector<proto::Odometry> odometry;
  std::vector<LinkObsBatch> batches;
};

Messages messages(RecordedSource& src, const RunOptions& o, int max_obs) {
  Messages m;
  m.config = link_config(src.sensor, o);
  m.reset = link_reset(src.x0, src.P0);
  std::vector<int> kept;
  for (const RunInput& in : src.inputs()) {
    m.is_scan.push_back(in.scan);
    if (in.scan) {
      m.batches.push_back(link_batch(in.observations, static_cast<std::uint32_t>(m.batches.size()),
                                     static_cast<std::size_t>(max_obs), kept));
    } else {
      m.odometry.push_back(link_odometry(in));
    }
  }
  return m;
}

/// The in-process baseline: the device's float step on the decoded messages. Returns seconds.
double in_process(const std::vector<Messages>& runs, long& scans) {
  auto step = std::make_unique<node::SlamStep<float, DesktopBounds>>();
  auto obs = std::make_unique<Observations<float, DesktopBounds>>();
  auto res = std::make_unique<node::StepResult<float, DesktopBounds>>();
  double secs = 0;
  scans = 0;
  for (const Messages& m : runs) {
    if (step->configure(node::settings_from<float, DesktopBounds>(m.config)) != Status::kOk) {
      throw std::runtime_error("in-process configure failed");
    }
    Pose2<float> x0;
    Mat3<float> P0;
    node::reset_from(m.reset, x0, P0);
    if (step->reset(x0, P0) != Status::kOk) throw std::runtime_error("in-process reset failed");
    std::size_t o = 0, b = 0;
    const auto t0 = Clock::now();
    for (const bool scan : m.is_scan) {
      if (!scan) {
        if (step->predict(node::odometry_from<float>(m.odometry[o++])) != Status::kOk) {
          throw std::runtime_error("in-process predict failed");
        }
        continue;
      }
      if (node::observations_from(m.batches[b++], *obs) != Status::kOk || step->step(*obs, *res) != Status::kOk) {
        throw std::runtime_error("in-process step failed");
      }
      ++scans;
    }
    secs += since(t0);
  }
  return secs;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  CLI::App app{"link_bench: end-to-end scans per second over the serial link, against the in-process step"};
  std::string scenario = std::string(GEOJCBB_SCENARIO_DIR) + "/dense.json";
  std::vector<std::string> names{"PCJCBB+RL", "GEOJCBB", "JCBB"};
  std::vector<int> windows{1, 8};
  int runs = 5, max_obs = 20, pings = 2000, repeats = 3;
  std::uint64_t seed = 1;
  LinkCli lc;
  const std::filesystem::path here = std::filesystem::path(argv[0]).parent_path();
  lc.device = (std::filesystem::exists(here / "geojcbb_device") ? here : here.parent_path()) / "geojcbb_device";
  lc.timeout_ms = 5000;
  add_link_options(app, lc, "the device's serial port or pty (default: start --device with --pty)",
                   "device program started when --port is not given");
  app.add_option("--scenario", scenario, "scenario JSON file")->default_val(scenario);
  app.add_option("--runs", runs, "seeds streamed per measurement (seed, seed+1, ...)")->default_val(runs);
  app.add_option("--seed", seed, "first seed")->default_val(seed);
  app.add_option("--strategies", names, std::string("strategies, comma separated (") + kPresetsHelp + ")")
      ->delimiter(',')
      ->default_str("GEOJCBB,JCBB");
  app.add_option("--windows", windows, "windows to measure, comma separated")->delimiter(',')->default_str("1,8");
  app.add_option("--max-obs", max_obs, "observations per scan, the nearest (at most 24)")
      ->default_val(max_obs)
      ->check(CLI::Range(1, static_cast<int>(kLinkMaxObs)));
  app.add_option("--pings", pings, "PING round trips timed")->default_val(pings);
  app.add_option("--repeat", repeats, "measurements of each cell; the best is reported")->default_val(repeats);
  CLI11_PARSE(app, argc, argv);
  try {
    const Scenario sc = load_scenario(scenario);
    std::vector<RecordedSource> sources;
    long scans_per_pass = 0, obs_per_pass = 0, full = 0;
    for (int r = 0; r < runs; ++r) {
      SimSource s(sc, seed + static_cast<std::uint64_t>(r));
      sources.emplace_back(s);
      for (const RunInput& in : sources.back().inputs()) {
        if (!in.scan) continue;
        const long n = std::min<long>(static_cast<long>(in.observations.size()), max_obs);
        ++scans_per_pass;
        obs_per_pass += n;
        full += n == max_obs;
      }
    }
    DeviceLink dl(lc, lc.port.empty());
    std::printf("%s\n", dl.describe().c_str());
    std::printf("%s: %d run(s), %ld scans, %.1f observations per scan on average (at most %d; %.0f%% of scans full)\n",
                sc.name.c_str(), runs, scans_per_pass, double(obs_per_pass) / double(scans_per_pass), max_obs,
                100.0 * double(full) / double(scans_per_pass));
    // The round trip of the link itself.
    double ping_s = 1e30;
    for (int rep = 0; rep < repeats; ++rep) {
      const auto t0 = Clock::now();
      for (int k = 0; k < pings; ++k) dl.session().ping(static_cast<std::uint32_t>(k));
      ping_s = std::min(ping_s, since(t0) / std::max(1, pings));
    }
    std::printf("PING round trip: %.1f us (best mean of %d x %d)\n", 1e6 * ping_s, repeats, pings);
    std::printf("\n  %-8s %14s %10s", "strategy", "in-process", "step [us]");
    for (int w : windows) std::printf("   link w=%-2d scans/s (ratio)", w);
    std::printf("\n");
    int status = 0;
    for (const Method& method : select_methods(names, false)) {
      const std::string name = method.name();
      RunOptions o;
      method.apply(o);
      std::vector<Messages> msgs;
      msgs.reserve(sources.size());
      for (RecordedSource& s : sources) msgs.push_back(messages(s, o, max_obs));
      double best_in = 1e30;
      long scans = 0;
      for (int rep = 0; rep < repeats; ++rep) best_in = std::min(best_in, in_process(msgs, scans));
      const double in_rate = double(scans) / best_in;
      std::printf("  %-8s %14.0f %10.1f", name.c_str(), in_rate, 1e6 / in_rate);
      std::vector<Score> scores;
      for (int w : windows) {
        StreamOptions st;
        st.window = w;
        st.max_observations = max_obs;
        double best = 1e30;
        Score total;
        for (int rep = 0; rep < repeats; ++rep) {
          total = Score{};
          const auto t0 = Clock::now();
          for (RecordedSource& s : sources) {
            s.rewind();
            total.add(stream_run(dl.session(), s, o, st).score);
          }
          best = std::min(best, since(t0));
        }
        scores.push_back(total);
        const double rate = double(scans) / best;
        std::printf("   %18.0f (%4.2fx)", rate, rate / in_rate);
        std::fflush(stdout);
      }
      for (const Score& s : scores) {
        if (s.tp != scores[0].tp || s.fp != scores[0].fp || s.fn != scores[0].fn || s.tn != scores[0].tn) status = 1;
      }
      std::printf("   %s\n", status == 0 ? "same results" : "RESULTS DIFFER");
    }
    std::printf(
        "\nstep [us]: the in-process step per scan (predictions included); ratios: link rate / in-process rate\n");
    if (dl.started_device()) dl.shut_down();
    return status;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "link_bench: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
