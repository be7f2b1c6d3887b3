// host_tools/qemu: the firmware on an emulated Cortex-M4F (QEMU's mps2-an386), as a device on a pty.
//   QemuMachine  starts qemu-system-arm halted (-S) with the UART on a pty and a QMP socket, finds
//                the pty with QMP query-chardev, and lets the caller open it before `cont` (QEMU
//                discards UART output while nobody holds the pty). Waits for the exit status that
//                the firmware passes through semihosting. No fixed sleeps: every wait is on a
//                condition with a deadline.
//   MirrorTransport  wraps the link to the device and runs the same node::Node in this process on
//                every byte the host sends; each ASSOC_RESULT and POSE the device answers is compared,
//                byte for byte, with the one the in-process node produced.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb_host/serial.hpp"

namespace geojcbb::host {

struct QemuOptions {
  std::string qemu = "qemu-system-arm";
  std::string machine = "mps2-an386";
  std::string elf;
  bool icount = true;  ///< -icount shift=0: one instruction per virtual ns (deterministic counts)
  int start_timeout_ms = 10000;
};

class QemuMachine {
 public:
  explicit QemuMachine(const QemuOptions& o);  ///< starts QEMU halted; throws std::runtime_error
  ~QemuMachine();                              ///< kills QEMU if it still runs
  QemuMachine(const QemuMachine&) = delete;
  QemuMachine& operator=(const QemuMachine&) = delete;
  /// The UART's pty (from QMP query-chardev, label serial0).
  const std::string& pty() const { return pty_; }
  /// Lets the CPU run (QMP cont).
  void cont();
  /// Waits at most timeout_ms for QEMU to exit. @return its exit status, or -1 on timeout or signal.
  int wait_exit(int timeout_ms);
  /// The QEMU command line, for messages.
  const std::string& command() const { return command_; }

 private:
  void start(const QemuOptions& o);
  void cleanup();                            ///< kills QEMU if it runs, closes and removes the socket
  std::string qmp(const std::string& json);  ///< sends one command, returns its reply line
  std::string read_line(int timeout_ms);
  pid_t pid_ = -1;
  int qmp_fd_ = -1;
  std::string socket_path_, pty_, command_, buffer_;
  bool exited_ = false;
  int status_ = -1;
};

}  // namespace geojcbb::host
