// geojcbb_link: streams a simulated scenario through a device over a serial link and scores what
// comes back (the evaluation's TP/TN/FP/FN and pose error). Without --port it starts
// geojcbb_device --pty beside itself, reads the pty's path and connects: the desktop loop.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <signal.h>
#include <strings.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/stream.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {
// Starts `program --pty`, returns its pid and the pty path from its first output line.
pid_t spawn_device(const std::string& program, std::string& path) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    close(fds[0]);
    close(fds[1]);
    execl(program.c_str(), program.c_str(), "--pty", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(fds[1]);
  FILE* f = fdopen(fds[0], "r");
  char line[512] = {0};
  const bool got = f != nullptr && std::fgets(line, sizeof line, f) != nullptr;
  if (f != nullptr) std::fclose(f);
  std::string s = got ? line : "";
  if (s.rfind("pty: ", 0) != 0) throw std::runtime_error("device did not report its pty: " + program);
  path = s.substr(5);
  while (!path.empty() && (path.back() == '\n' || path.back() == '\r')) path.pop_back();
  return pid;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"geojcbb_link: stream a simulated scenario through a device over a serial link and score the replies"};
  std::string port, scenario = std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json";
  std::string device = (std::filesystem::path(argv[0]).parent_path() / "geojcbb_device").string();
  std::vector<std::string> names;
  std::uint64_t seed = 1;
  int timeout_ms = 2000;
  RunOptions o;
  app.add_option("--port", port, "device's serial port or pty (default: start geojcbb_device --pty)");
  app.add_option("--device", device, "device program started when --port is not given")->default_val(device);
  app.add_option("--scenario", scenario, "scenario JSON file")->default_val(scenario);
  app.add_option("--strategies", names, "strategies, comma separated (default: all six)")->delimiter(',');
  app.add_option("--seed", seed, "simulation seed")->default_val(seed);
  app.add_option("--max-steps", o.max_steps, "control intervals to stream (0: the whole path)")->default_val(0);
  app.add_option("--timeout-ms", timeout_ms, "wait for each reply at most this long")->default_val(timeout_ms);
  CLI11_PARSE(app, argc, argv);
  pid_t child = -1;
  int rc = 0;
  try {
    if (port.empty()) child = spawn_device(device, port);
    const Scenario sc = load_scenario(scenario);
    PosixSerial serial(port);
    LinkClient link(serial, timeout_ms);
    const proto::Capabilities caps = link.hello();
    std::printf("device on %s: boot id %08x, %d-byte scalars, up to %u observations, %u landmarks; schema %08x\n",
                port.c_str(), caps.boot_id, caps.scalar_bytes, caps.max_observations, caps.max_landmarks,
                caps.schema_hash);
    std::vector<Strategy> strategies;
    for (int k = 0; k < kStrategyCount; ++k) {
      const Strategy s = static_cast<Strategy>(k);
      bool take = names.empty();
      for (const std::string& n : names) take = take || strcasecmp(n.c_str(), to_string(s)) == 0;
      if (take) strategies.push_back(s);
    }
    std::printf("%s, seed %llu, streamed over the link\n", sc.name.c_str(), static_cast<unsigned long long>(seed));
    std::printf("  %-8s %6s %8s %7s %6s %6s %10s %8s %8s %10s %10s %12s\n", "strategy", "scans", "TP", "TN", "FP", "FN",
                "precision", "recall", "F1", "|x err| m", "|y err| m", "scans/s");
    for (Strategy s : strategies) {
      const auto t0 = std::chrono::steady_clock::now();
      const RunResult r = stream_scenario(link, sc, seed, s, o);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("  %-8s %6d %8d %7d %6d %6d %10.4f %8.4f %8.4f %10.4f %10.4f %12.0f\n", to_string(s), r.scans,
                  r.score.tp, r.score.tn, r.score.fp, r.score.fn, r.score.precision(), r.score.recall(), r.score.f1(),
                  r.mean_abs_x_m, r.mean_abs_y_m, r.scans / secs);
      const proto::Capabilities again = link.hello();
      if (again.boot_id != caps.boot_id) std::printf("  (the device restarted: boot id %08x)\n", again.boot_id);
    }
    const proto::Stats st = link.stats();
    std::printf("device STATS: frames ok %u, bad CRC %u, bad length %u, overrun %u, unknown type %u, invalid field %u, "
                "scans %u, budget hits %u\n",
                st.frames_ok, st.bad_crc, st.bad_length, st.overrun, st.unknown_type, st.invalid_field, st.scans,
                st.budget_hits);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geojcbb_link: %s\n", e.what());
    rc = 1;
  }
  if (child > 0) {
    kill(child, SIGTERM);
    waitpid(child, nullptr, 0);
  }
  return rc;
}
