// geojcbb_device: the firmware's device loop (node::Node, float, DesktopBounds or with --default-bounds
// DefaultBounds) on a serial port or
// on a new pseudo-terminal, whose path it prints as "pty: PATH". Runs until SIGINT/SIGTERM, until
// the port closes, or until a SHUTDOWN message, whose exit code it exits with.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "geojcbb_host/link.hpp"
#include "geojcbb_host/guarded_main.hpp"

namespace {
std::atomic<bool> g_stop{false};
}

namespace {

int run(int argc, char** argv) {
  CLI::App app{"geojcbb_device: the device loop of the firmware (float) on a serial port or a pseudo-terminal"};
  std::string port;
  bool pty = false;
  int baud = 115200;
  auto* p = app.add_option("--port", port, "serial port to serve (e.g. /dev/ttyUSB0)");
  app.add_flag("--pty", pty, "create a pseudo-terminal and print its path as 'pty: PATH'")->excludes(p);
  app.add_option("--baud", baud, "baud rate of --port")->default_val(baud);
  std::string transport = "auto";
  app.add_option("--transport", transport,
                 "transport of --port: auto (termios for /dev/pts/*, else libserialport), termios or libserialport")
      ->check(CLI::IsMember({"auto", "termios", "libserialport"}))
      ->default_val(transport);
  bool default_bounds = false;
  app.add_flag("--default-bounds", default_bounds,
               "the default firmware's bounds (96 landmarks, as the 128 KiB Cortex-M4F image) instead of the large "
               "firmware's");
  bool list = false;
  app.add_flag("--list-ports", list, "print the serial ports libserialport finds and exit");
  CLI11_PARSE(app, argc, argv);
  if (list) {
    try {
      for (const geojcbb::host::PortInfo& i : geojcbb::host::list_ports())
        std::printf("%s\n", geojcbb::host::port_line(i).c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "geojcbb_device: %s\n", e.what());
      return 1;
    }
    return 0;
  }
  if (!pty && port.empty()) {
    std::fprintf(stderr, "geojcbb_device: give --pty or --port PATH\n");
    return 2;
  }
  std::signal(SIGINT, [](int) { g_stop = true; });
  std::signal(SIGTERM, [](int) { g_stop = true; });
  const auto boot_id = static_cast<std::uint32_t>(std::chrono::steady_clock::now().time_since_epoch().count() ^
                                                  static_cast<long long>(getpid()));
  try {
    std::unique_ptr<geojcbb::host::Transport> t;
    if (pty) {
      auto q = std::make_unique<geojcbb::host::Pty>();
      std::printf("pty: %s\n", q->slave_path().c_str());
      std::fflush(stdout);
      t = std::move(q);
    } else {
      t = geojcbb::host::open_transport(port, baud, geojcbb::host::parse_transport_kind(transport));
    }
    const geojcbb::host::ServeResult r = geojcbb::host::serve_device(*t, g_stop, boot_id, default_bounds);
    if (r.shutdown_code) {
      std::fprintf(stderr, "geojcbb_device: SHUTDOWN with exit code %d after %llu bytes\n", *r.shutdown_code,
                   static_cast<unsigned long long>(r.bytes));
      return *r.shutdown_code;
    }
    std::fprintf(stderr, "geojcbb_device: stopped after %llu bytes\n", static_cast<unsigned long long>(r.bytes));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geojcbb_device: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
