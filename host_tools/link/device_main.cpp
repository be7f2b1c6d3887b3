// geojcbb_device: the firmware's device loop (node::Node, float, DesktopBounds) on a serial port or
// on a new pseudo-terminal, whose path it prints as "pty: PATH". Runs until SIGINT/SIGTERM or until
// the port closes.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "geojcbb_host/link.hpp"

namespace {
std::atomic<bool> g_stop{false};
}

int main(int argc, char** argv) {
  CLI::App app{"geojcbb_device: the device loop of the firmware (float) on a serial port or a pseudo-terminal"};
  std::string port;
  bool pty = false;
  int baud = 115200;
  auto* p = app.add_option("--port", port, "serial port to serve (e.g. /dev/ttyUSB0)");
  app.add_flag("--pty", pty, "create a pseudo-terminal and print its path as 'pty: PATH'")->excludes(p);
  app.add_option("--baud", baud, "baud rate of --port")->default_val(baud);
  CLI11_PARSE(app, argc, argv);
  if (!pty && port.empty()) {
    std::fprintf(stderr, "geojcbb_device: give --pty or --port PATH\n");
    return 2;
  }
  std::signal(SIGINT, [](int) { g_stop = true; });
  std::signal(SIGTERM, [](int) { g_stop = true; });
  const auto boot_id = static_cast<std::uint32_t>(
      std::chrono::steady_clock::now().time_since_epoch().count() ^ static_cast<long long>(getpid()));
  try {
    std::unique_ptr<geojcbb::host::Transport> t;
    if (pty) {
      auto q = std::make_unique<geojcbb::host::Pty>();
      std::printf("pty: %s\n", q->slave_path().c_str());
      std::fflush(stdout);
      t = std::move(q);
    } else {
      t = std::make_unique<geojcbb::host::PosixSerial>(port, baud);
    }
    const std::uint64_t bytes = geojcbb::host::serve_device(*t, g_stop, boot_id);
    std::fprintf(stderr, "geojcbb_device: stopped after %llu bytes\n", static_cast<unsigned long long>(bytes));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geojcbb_device: %s\n", e.what());
    return 1;
  }
  return 0;
}
