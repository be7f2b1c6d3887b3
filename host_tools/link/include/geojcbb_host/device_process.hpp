// host_tools/link: a device program started beside the host tool, for the desktop loop and the
// tests: `program [its arguments] --pty` runs the device on a new pseudo-terminal and prints its path
// as the first line of its output ("pty: PATH"). Used by geojcbb_link (without --port) and geojcbb_eval --device.
// DeviceLink is a host program's connection: start a device when asked, open a reconnecting
// LinkSession on the port, and at the end shut a started device down.
#pragma once

#include <sys/types.h>

#include <memory>
#include <string>

#include "geojcbb_host/session.hpp"

namespace geojcbb::host {

class DeviceProcess {
 public:
  /// Starts `program --pty` and reads the pty's path. Throws std::runtime_error when the program
  /// cannot be started or does not report a pty.
  explicit DeviceProcess(const std::string& program);
  /// Ends the process (SIGTERM) unless it has exited, and reaps it.
  ~DeviceProcess();
  DeviceProcess(const DeviceProcess&) = delete;
  DeviceProcess& operator=(const DeviceProcess&) = delete;
  /// The pseudo-terminal to connect to.
  const std::string& port() const { return port_; }
  pid_t pid() const { return pid_; }
  /// Waits up to timeout_ms for the process to exit by itself (after a SHUTDOWN, say). Returns its
  /// exit code, or -1 when it did not exit in time or was ended by a signal.
  int wait_exit(int timeout_ms);

 private:
  pid_t pid_ = -1;
  std::string port_;
};

/// The device-link settings of a host program (options: link_cli.hpp, add_link_options).
struct LinkCli {
  std::string port;    ///< the device's serial port or pty
  std::string device;  ///< a device program to start with --pty (its pty becomes the port)
  std::string transport = "auto";
  int baud = 115200;
  int timeout_ms = 2000;
  int window = 1;
  int reconnect_ms = 10000;
  int max_restarts = 3;
};

/// A host program's connection to its device.
class DeviceLink {
 public:
  /// Starts cli.device --pty when `start_device` (its pty is the port), then opens the session.
  DeviceLink(const LinkCli& cli, bool start_device);
  ~DeviceLink();
  LinkSession& session() { return *session_; }
  const std::string& port() const { return port_; }
  bool started_device() const { return process_ != nullptr; }
  /// "device on PORT: boot id ..., N-byte scalars, up to N observations, N landmarks; schema ...".
  std::string describe();
  /// A device started here: SHUTDOWN with exit code 0, then its exit. Returns the exit code (-1
  /// when it did not exit); 0 without a started device.
  int shut_down();

 private:
  std::unique_ptr<DeviceProcess> process_;
  std::string port_;
  std::unique_ptr<LinkSession> session_;
};

}  // namespace geojcbb::host
