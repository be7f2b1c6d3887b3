// The libserialport transport (SpSerial), port enumeration (list_ports) and the transport factory
// (open_transport). docs/protocol.md, "Transports", says which backend is used when and how the
// libserialport backend is tested on a pseudo-terminal.
#include <libserialport.h>
#include <poll.h>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "geojcbb_host/serial.hpp"

namespace geojcbb::host {

namespace {
/// libserialport's text for a failed call: sp_last_error_message() (the OS error) for SP_ERR_FAIL,
/// which is the only code it keeps a message for; a fixed text for the others.
std::string sp_message(int code) {
  switch (code) {
    case SP_ERR_FAIL: {
      char* m = sp_last_error_message();
      std::string s = m != nullptr ? m : "unknown OS error";
      sp_free_error_message(m);
      return s;
    }
    case SP_ERR_ARG: return "invalid argument";
    case SP_ERR_MEM: return "out of memory";
    case SP_ERR_SUPP: return "not supported on this platform";
    default: return "error " + std::to_string(code);
  }
}

std::string str_or_empty(const char* s) { return s != nullptr ? s : ""; }

struct PortListDeleter {
  void operator()(sp_port** l) const { sp_free_port_list(l); }
};
}  // namespace

SpSerial::SpSerial(const std::string& name, int baud, int write_timeout_ms)
    : name_(name), write_timeout_ms_(write_timeout_ms) {
  if (baud <= 0) throw std::runtime_error("libserialport: " + name + ": invalid baud rate " + std::to_string(baud));
  if (write_timeout_ms <= 0) throw std::runtime_error("libserialport: write timeout must be > 0 ms");
  const sp_return r = sp_get_port_by_name(name.c_str(), &port_);
  if (r != SP_OK) {
    port_ = nullptr;
    if (r == SP_ERR_ARG) {
      // Its lookup wants /dev/NAME with a /sys/class/tty/NAME entry: pseudo-terminals have none.
      throw std::runtime_error("libserialport: " + name +
                               ": not a serial port it knows (no /sys/class/tty entry; for a pseudo-terminal use "
                               "--transport termios)");
    }
    fail("look up", r);
  }
  try {
    sp_return e = sp_open(port_, SP_MODE_READ_WRITE);
    if (e != SP_OK) fail("open", e);
    sp_port_config* cfg = nullptr;
    if ((e = sp_new_config(&cfg)) != SP_OK) fail("configure", e);
    // 8N1, no flow control (which also asserts RTS and DTR), at the requested rate.
    e = sp_set_config_baudrate(cfg, baud);
    if (e == SP_OK) e = sp_set_config_bits(cfg, 8);
    if (e == SP_OK) e = sp_set_config_parity(cfg, SP_PARITY_NONE);
    if (e == SP_OK) e = sp_set_config_stopbits(cfg, 1);
    if (e == SP_OK) e = sp_set_config_flowcontrol(cfg, SP_FLOWCONTROL_NONE);
    if (e == SP_OK) e = sp_set_config(port_, cfg);
    const std::string msg = e == SP_OK ? "" : sp_message(e);
    sp_free_config(cfg);
    if (e != SP_OK) {
      throw std::runtime_error("libserialport: configure " + name_ + " (" + std::to_string(baud) + " 8N1): " + msg);
    }
    if ((e = sp_new_event_set(&rx_)) != SP_OK) fail("event set for", e);
    if ((e = sp_add_port_events(rx_, port_, static_cast<sp_event>(SP_EVENT_RX_READY | SP_EVENT_ERROR))) != SP_OK) {
      fail("event set for", e);
    }
  } catch (...) {
    if (rx_ != nullptr) sp_free_event_set(rx_);
    sp_close(port_);  // SP_ERR_ARG when it never opened: nothing to do
    sp_free_port(port_);
    rx_ = nullptr;
    port_ = nullptr;
    throw;
  }
}

SpSerial::~SpSerial() {
  if (rx_ != nullptr) sp_free_event_set(rx_);
  if (port_ != nullptr) {
    sp_close(port_);
    sp_free_port(port_);
  }
}

void SpSerial::fail(const std::string& what, int code) const {
  throw std::runtime_error("libserialport: " + what + " " + name_ + ": " + sp_message(code));
}

bool SpSerial::hung_up() const {
  int fd = -1;
  if (sp_get_port_handle(port_, &fd) != SP_OK || fd < 0) return true;
  pollfd pfd{fd, POLLIN, 0};
  if (poll(&pfd, 1, 0) < 0) return false;
  return (pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0;
}

std::size_t SpSerial::read(std::uint8_t* p, std::size_t n, int timeout_ms) {
  if (n == 0) return 0;
  const std::size_t want = std::min<std::size_t>(n, INT_MAX);
  const auto take = [&]() -> std::size_t {
    const int got = sp_nonblocking_read(port_, p, want);
    if (got < 0) fail("read", got);
    return static_cast<std::size_t>(got);
  };
  std::size_t got = take();
  if (got > 0) return got;
  if (timeout_ms > 0) {  // sp_wait's 0 means "forever"
    const sp_return w = sp_wait(rx_, static_cast<unsigned>(timeout_ms));
    if (w != SP_OK) fail("wait on", w);
    got = take();
    if (got > 0) return got;
  }
  // Nothing to read: a timeout, unless the line hung up (a tty whose device went away reads 0
  // bytes at once; a pty slave whose master closed fails the read above with EIO).
  if (hung_up()) throw std::runtime_error("libserialport: " + name_ + ": closed");
  return 0;
}

void SpSerial::write(const std::uint8_t* p, std::size_t n) {
  while (n > 0) {
    const std::size_t chunk = std::min<std::size_t>(n, INT_MAX);
    const int w = sp_blocking_write(port_, p, chunk, static_cast<unsigned>(write_timeout_ms_));
    if (w < 0) fail("write", w);
    if (static_cast<std::size_t>(w) < chunk) {
      throw std::runtime_error("libserialport: write " + name_ + ": timed out after " +
                               std::to_string(write_timeout_ms_) + " ms (" + std::to_string(w) + " of " +
                               std::to_string(chunk) + " bytes written)");
    }
    p += w;
    n -= static_cast<std::size_t>(w);
  }
}

std::vector<PortInfo> list_ports() {
  sp_port** raw = nullptr;
  const sp_return r = sp_list_ports(&raw);
  if (r != SP_OK) throw std::runtime_error("libserialport: list ports: " + sp_message(r));
  const std::unique_ptr<sp_port*, PortListDeleter> list(raw);
  std::vector<PortInfo> out;
  for (sp_port** q = list.get(); *q != nullptr; ++q) {
    PortInfo i;
    i.name = str_or_empty(sp_get_port_name(*q));
    i.description = str_or_empty(sp_get_port_description(*q));
    switch (sp_get_port_transport(*q)) {
      case SP_TRANSPORT_USB: {
        i.transport = "usb";
        int vid = -1, pid = -1;
        if (sp_get_port_usb_vid_pid(*q, &vid, &pid) == SP_OK) {
          i.usb_vid = vid;
          i.usb_pid = pid;
        }
        i.usb_manufacturer = str_or_empty(sp_get_port_usb_manufacturer(*q));
        i.usb_product = str_or_empty(sp_get_port_usb_product(*q));
        i.usb_serial = str_or_empty(sp_get_port_usb_serial(*q));
        break;
      }
      case SP_TRANSPORT_BLUETOOTH:
        i.transport = "bluetooth";
        i.bluetooth_address = str_or_empty(sp_get_port_bluetooth_address(*q));
        break;
      default: i.transport = "native"; break;
    }
    out.push_back(std::move(i));
  }
  std::sort(out.begin(), out.end(), [](const PortInfo& a, const PortInfo& b) { return a.name < b.name; });
  return out;
}

std::string port_line(const PortInfo& p) {
  std::string s = p.name + "  " + p.transport;
  if (p.usb_vid >= 0 && p.usb_pid >= 0) {
    char id[24];
    std::snprintf(id, sizeof id, " %04x:%04x", static_cast<unsigned>(p.usb_vid), static_cast<unsigned>(p.usb_pid));
    s += id;
  }
  if (!p.usb_serial.empty()) s += " serial " + p.usb_serial;
  if (!p.bluetooth_address.empty()) s += " " + p.bluetooth_address;
  if (!p.usb_manufacturer.empty()) s += "  " + p.usb_manufacturer;
  if (!p.description.empty()) s += "  " + p.description;
  return s;
}

TransportKind parse_transport_kind(const std::string& s) {
  if (s == "auto") return TransportKind::kAuto;
  if (s == "termios") return TransportKind::kTermios;
  if (s == "libserialport") return TransportKind::kLibserialport;
  throw std::invalid_argument("unknown transport '" + s + "' (auto, termios or libserialport)");
}

const char* transport_kind_name(TransportKind k) {
  switch (k) {
    case TransportKind::kTermios: return "termios";
    case TransportKind::kLibserialport: return "libserialport";
    default: return "auto";
  }
}

TransportKind resolve_transport_kind(const std::string& path, TransportKind k) {
  if (k != TransportKind::kAuto) return k;
  std::string real = path;
  if (char* r = realpath(path.c_str(), nullptr)) {  // a symlink to a pty (socat's links, say) is a pty
    real = r;
    std::free(r);
  }
  return real.rfind("/dev/pts/", 0) == 0 ? TransportKind::kTermios : TransportKind::kLibserialport;
}

std::unique_ptr<Transport> open_transport(const std::string& path, int baud, TransportKind kind) {
  if (resolve_transport_kind(path, kind) == TransportKind::kTermios) return std::make_unique<PosixSerial>(path, baud);
  return std::make_unique<SpSerial>(path, baud);
}

}  // namespace geojcbb::host
