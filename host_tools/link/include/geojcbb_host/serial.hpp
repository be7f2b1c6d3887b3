// host_tools/link: byte transports to a device, behind one interface.
//   SpSerial       libserialport: real serial ports (/dev/ttyUSB0, /dev/ttyACM0, /dev/ttyS0).
//   PosixSerial    termios on any tty path: a real UART or a pseudo-terminal (/dev/pts/N).
//                  libserialport 0.1.1 cannot open ptys (its lookup needs a sysfs entry and
//                  sp_open the modem-line ioctls), so ptys go through termios.
//   Pty            creates a pseudo-terminal pair: the device side serves the master, a client
//                  opens slave_path() with PosixSerial (or SpSerial in the shimmed test).
//   open_transport picks one of the two by path (docs/protocol.md, "Transports");
//   list_ports     the serial ports libserialport finds (sp_list_ports).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

struct sp_port;
struct sp_event_set;

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

/// A serial port through libserialport, raw 8N1 at `baud`, no flow control (RTS and DTR asserted).
/// read() waits with sp_wait for the first byte and takes what is there; write() is
/// sp_blocking_write, and a write that has not finished after `write_timeout_ms` throws.
/// libserialport's own messages (sp_last_error_message) are in the exceptions.
class SpSerial : public Transport {
 public:
  explicit SpSerial(const std::string& name, int baud = 115200, int write_timeout_ms = 5000);
  ~SpSerial() override;
  SpSerial(const SpSerial&) = delete;
  SpSerial& operator=(const SpSerial&) = delete;
  std::size_t read(std::uint8_t* p, std::size_t n, int timeout_ms) override;
  void write(const std::uint8_t* p, std::size_t n) override;
  const std::string& name() const { return name_; }

 private:
  [[noreturn]] void fail(const std::string& what, int code) const;
  bool hung_up() const;
  sp_port* port_ = nullptr;
  sp_event_set* rx_ = nullptr;
  std::string name_;
  int write_timeout_ms_;
};

/// A serial port as libserialport describes it.
struct PortInfo {
  std::string name;         ///< e.g. /dev/ttyUSB0
  std::string description;  ///< USB product name, or the device name
  std::string transport;    ///< "native", "usb" or "bluetooth"
  int usb_vid = -1;         ///< USB only, else -1
  int usb_pid = -1;
  std::string usb_manufacturer, usb_product, usb_serial;  ///< USB only, when the device reports them
  std::string bluetooth_address;                          ///< Bluetooth only
};

/// The serial ports present (sp_list_ports; pseudo-terminals and virtual consoles are not listed).
/// Throws std::runtime_error when enumeration fails.
std::vector<PortInfo> list_ports();
/// One line for --list-ports: name, transport, USB VID:PID and serial where known, description.
std::string port_line(const PortInfo& p);

enum class TransportKind { kAuto, kTermios, kLibserialport };
/// "auto", "termios" or "libserialport" (the --transport values); throws std::invalid_argument.
TransportKind parse_transport_kind(const std::string& s);
const char* transport_kind_name(TransportKind k);
/// What kAuto chooses for `path`: termios for a pseudo-terminal (/dev/pts/N, also through a
/// symlink), libserialport for anything else.
TransportKind resolve_transport_kind(const std::string& path, TransportKind k = TransportKind::kAuto);
/// Opens `path` with the transport `kind` resolves to (PosixSerial or SpSerial).
std::unique_ptr<Transport> open_transport(const std::string& path, int baud = 115200,
                                          TransportKind kind = TransportKind::kAuto);

}  // namespace geojcbb::host
