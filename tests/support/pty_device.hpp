// Tests: the desktop device (node::Node in float) serving the master side of a pseudo-terminal in a
// thread, for tests that talk to it through a host transport on pty.slave_path().
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>

#include "geojcbb_host/link.hpp"
#include "geojcbb_host/serial.hpp"

namespace geojcbb::test {

struct PtyDevice {
  host::Pty pty;
  std::atomic<bool> stop{false};
  std::thread thread;
  explicit PtyDevice(std::uint32_t boot_id) : thread([this, boot_id] { host::serve_device(pty, stop, boot_id); }) {}
  ~PtyDevice() {
    stop = true;
    thread.join();
  }
  PtyDevice(const PtyDevice&) = delete;
  PtyDevice& operator=(const PtyDevice&) = delete;
};

}  // namespace geojcbb::test
