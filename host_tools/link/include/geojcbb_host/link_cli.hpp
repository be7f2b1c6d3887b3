// host_tools/link: the device-link options shared by the host programs (geojcbb_link, geojcbb_eval),
// for CLI11; the connection they describe is DeviceLink (device_process.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "geojcbb_host/device_process.hpp"

namespace geojcbb::host {

/// Adds --port, --device (when device_help is not null), --baud, --transport, --timeout-ms,
/// --window, --reconnect-ms and --max-restarts to `app`, bound to `o`.
inline void add_link_options(CLI::App& app, LinkCli& o, const std::string& port_help, const char* device_help) {
  app.add_option("--port", o.port, port_help);
  if (device_help != nullptr) app.add_option("--device", o.device, device_help);
  app.add_option("--baud", o.baud, "baud rate of --port")->default_val(o.baud);
  app.add_option("--transport", o.transport,
                 "transport of --port: auto (termios for /dev/pts/*, else libserialport), termios or libserialport")
      ->check(CLI::IsMember({"auto", "termios", "libserialport"}))
      ->default_val(o.transport);
  app.add_option("--timeout-ms", o.timeout_ms, "wait for each reply at most this long; then reconnect")
      ->default_val(o.timeout_ms)
      ->check(CLI::Range(1, 3600000));
  app.add_option("--window", o.window,
                 "scans in flight: OBS_BATCHes sent ahead of their replies (the results do not depend on it)")
      ->default_val(o.window)
      ->check(CLI::Range(1, 64));
  app.add_option("--reconnect-ms", o.reconnect_ms,
                 "after a closed port or a timeout, reopen and handshake again for at most this long")
      ->default_val(o.reconnect_ms)
      ->check(CLI::Range(1, 3600000));
  app.add_option("--max-restarts", o.max_restarts,
                 "times a run may start again from the beginning after the device lost its state")
      ->default_val(o.max_restarts)
      ->check(CLI::Range(0, 1000));
}

}  // namespace geojcbb::host
