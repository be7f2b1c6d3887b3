// host_tools/link: byte transports to a device, behind one interface.
//   PosixSerial  termios on any tty path: a real UART (/dev/ttyUSB0) or a pseudo-terminal
//                (/dev/pts/N). libserialport 0.1.1 cannot open ptys (its lookup needs a sysfs
//                entry and sp_open the modem-line ioctls), so ptys go through termios.
//   Pty          creates a pseudo-terminal pair: the device side serves the master, a client
//                opens slave_path() with PosixSerial.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace geojcbb::host {

class Transport {
 public:
  virtual ~Transport() = default;
  /// Reads up to n bytes; waits at most timeout_ms for the first. Returns the count (0: timeout).
  /// Throws std::runtime_error when the port is closed or fails.
  virtual std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) = 0;
  /// Writes all n bytes. Throws std::runtime_error on failure.
  virtual void write(const std::uint8_t* p, std::size_t n) = 0;
};

/// A tty in raw mode (8N1, no flow control) at `baud` (ignored by ptys).
class PosixSerial : public Transport {
 public:
  PosixSerial(const std::string& path, int baud = 115200);
  ~PosixSerial() override;
  PosixSerial(const PosixSerial&) = delete;
  PosixSerial& operator=(const PosixSerial&) = delete;
  std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) override;
  void write(const std::uint8_t* p, std::size_t n) override;
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  std::string path_;
};

/// A pseudo-terminal pair in raw mode; the master stays open for the object's life.
class Pty : public Transport {
 public:
  Pty();
  ~Pty() override;
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  const std::string& slave_path() const { return slave_; }
  std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) override;
  void write(const std::uint8_t* p, std::size_t n) override;

 private:
  int master_ = -1;
  int slave_keep_ = -1;  ///< keeps the slave open so the master never sees a hang-up
  std::string slave_;
};

}  // namespace geojcbb::host
