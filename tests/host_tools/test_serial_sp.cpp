// The libserialport transport (SpSerial) on a pseudo-terminal, through the test-only shim in
// tests/support/sp_pty_shim.cpp (linked into this executable only): first what libserialport 0.1.1
// does on a pty without the shim, then bytes both ways, timeouts, a closed peer, the transport
// factory, port enumeration, and a whole LinkClient session over SpSerial that must equal the same
// session over the termios transport.
#include <doctest/doctest.h>
#include <libserialport.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "geojcbb_host/stream.hpp"
#include "support/sp_pty_shim.hpp"
#include "support/pty_device.hpp"

using namespace geojcbb;
using namespace geojcbb::host;
namespace shim = geojcbb::test::sp_pty_shim;

namespace {
// libserialport's debug output, collected while a test case listens.
std::mutex g_log_mu;
std::string g_log;
void collect(const char* format, ...) {
  char line[512];
  va_list ap;
  va_start(ap, format);
  std::vsnprintf(line, sizeof line, format, ap);
  va_end(ap);
  const std::lock_guard<std::mutex> lock(g_log_mu);
  g_log += line;
}
struct ListenToLibserialport {
  ListenToLibserialport() {
    g_log.clear();
    sp_set_debug_handler(collect);
  }
  ~ListenToLibserialport() { sp_set_debug_handler(sp_default_debug_handler); }
  std::string log() const {
    const std::lock_guard<std::mutex> lock(g_log_mu);
    return g_log;
  }
};

// Reads from `t` until `n` bytes arrived or `ms` passed.
std::vector<std::uint8_t> read_n(Transport& t, std::size_t n, int ms = 5000) {
  std::vector<std::uint8_t> out(n);
  std::size_t got = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  while (got < n && std::chrono::steady_clock::now() < end) got += t.read(out.data() + got, n - got, 50);
  out.resize(got);
  return out;
}

std::vector<std::uint8_t> pattern(std::size_t n, std::uint32_t seed) {
  std::vector<std::uint8_t> v(n);
  std::uint32_t x = seed;
  for (auto& b : v) {
    x = x * 1664525u + 1013904223u;
    b = static_cast<std::uint8_t>(x >> 24);
  }
  return v;
}

using Device = geojcbb::test::PtyDevice;

template <class M>
std::vector<std::uint8_t> bytes_of(const M& m) {
  std::vector<std::uint8_t> b(M::kMaxPayloadSize);
  std::size_t n = 0;
  REQUIRE(m.encode(b.data(), b.size(), n) == proto::Error::kOk);
  b.resize(n);
  return b;
}

// A short session: HELLO, then CONFIG, RESET and the first control intervals of env1 (ODOMETRY and
// OBS_BATCH, answered by ASSOC_RESULT and POSE), then STATS. Every reply payload, in order.
struct Session {
  std::vector<std::uint8_t> capabilities;
  std::vector<std::vector<std::uint8_t>> replies;
  RunResult run;
  proto::Stats stats;
};
Session session(bool libserialport) {
  const Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  Device dev(0x5E55);
  std::unique_ptr<Transport> port;
  if (libserialport) {
    port = std::make_unique<SpSerial>(dev.pty.slave_path());
  } else {
    port = std::make_unique<PosixSerial>(dev.pty.slave_path());
  }
  LinkClient link(*port);
  Session s;
  s.capabilities = bytes_of(link.hello());
  RunOptions o;
  o.max_steps = 120;
  s.run = stream_scenario(link, sc, 5, o, [&](const LinkObsBatch&, const LinkClient::ScanReply& r) {
    s.replies.push_back(bytes_of(r.result));
    s.replies.push_back(bytes_of(r.pose));
  });
  s.stats = link.stats();
  return s;
}
}  // namespace

TEST_CASE("libserialport 0.1.1 alone cannot open a pty: the sysfs lookup fails, then the modem-line ioctls") {
  Pty pty;
  ListenToLibserialport listen;
  SUBCASE("without the sysfs half: sp_get_port_by_name finds no /sys/class/tty/pts/N") {
    shim::set_sysfs(false);
    sp_port* p = nullptr;
    CHECK(sp_get_port_by_name(pty.slave_path().c_str(), &p) == SP_ERR_ARG);
    CHECK(p == nullptr);
    CHECK_THROWS_WITH_AS(SpSerial{pty.slave_path()}, doctest::Contains("no /sys/class/tty entry"), std::runtime_error);
    CHECK(listen.log().find("get_port_details returning SP_ERR_ARG: Device not found") != std::string::npos);
  }
  SUBCASE("without the modem-line half: sp_open fails on TIOCMGET (ENOTTY)") {
    shim::set_modem_lines(false);
    int bits = 0;
    PosixSerial raw(pty.slave_path());
    const int r = ioctl(raw.fd(), TIOCMGET, &bits);  // the pty driver has no modem lines
    const int err = errno;
    CHECK(r == -1);
    CHECK(err == ENOTTY);
    CHECK_THROWS_WITH_AS(SpSerial{pty.slave_path()}, doctest::Contains("Inappropriate ioctl for device"),
                         std::runtime_error);
    CHECK(listen.log().find("TIOCMGET ioctl failed") != std::string::npos);
  }
  shim::set_sysfs(true);
  shim::set_modem_lines(true);
}

TEST_CASE("SpSerial on a pty (through the shim): bytes both ways, modem lines set as on a UART") {
  Pty pty;
  const shim::Counts before = shim::counts();
  SpSerial port(pty.slave_path(), 115200);
  const shim::Counts after = shim::counts();
  CHECK(after.sysfs_lookups > before.sysfs_lookups);  // lstat + readlink of /sys/class/tty/pts/N
  CHECK(after.modem_get > before.modem_get);          // get_config's TIOCMGET
  CHECK(after.modem_set > before.modem_set);          // set_config's TIOCMBIS for RTS and DTR
  const int lines = shim::modem_lines(pty.slave_path().c_str());
  CHECK((lines & TIOCM_DTR) != 0);
  CHECK((lines & TIOCM_RTS) != 0);

  // NUL, XON/XOFF, CR/LF pass untouched (raw mode).
  const std::vector<std::uint8_t> up = {'H', 'E', 'L', 'L', 'O', 0x00, 0x11, 0x13, '\r', '\n', 0xff};
  port.write(up.data(), up.size());
  CHECK(read_n(pty, up.size()) == up);
  const std::vector<std::uint8_t> down = pattern(300, 7);
  pty.write(down.data(), down.size());
  CHECK(read_n(port, down.size()) == down);

  // More than the pty's buffers hold, each way, with the other side reading concurrently.
  const std::vector<std::uint8_t> big_up = pattern(200000, 1), big_down = pattern(150000, 2);
  std::vector<std::uint8_t> got_up, got_down;
  std::thread reader([&] { got_up = read_n(pty, big_up.size(), 20000); });
  port.write(big_up.data(), big_up.size());
  reader.join();
  CHECK(got_up == big_up);
  std::thread writer([&] { pty.write(big_down.data(), big_down.size()); });
  got_down = read_n(port, big_down.size(), 20000);
  writer.join();
  CHECK(got_down == big_down);
}

TEST_CASE("SpSerial: a read with nothing to read returns 0 after its timeout") {
  Pty pty;
  SpSerial port(pty.slave_path());
  std::uint8_t buf[64];
  auto t0 = std::chrono::steady_clock::now();
  CHECK(port.read(buf, sizeof buf, 150) == 0u);
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CHECK(waited >= 0.12);
  CHECK(waited < 2.0);
  t0 = std::chrono::steady_clock::now();
  CHECK(port.read(buf, sizeof buf, 0) == 0u);  // 0: do not wait (sp_wait's 0 would wait forever)
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 0.1);
  // A byte arriving during the wait ends it early.
  std::thread late([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const std::uint8_t b = 0x5A;
    pty.write(&b, 1);
  });
  t0 = std::chrono::steady_clock::now();
  CHECK(port.read(buf, sizeof buf, 3000) == 1u);
  CHECK(buf[0] == 0x5A);
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 2.0);
  late.join();
}

TEST_CASE("SpSerial: a closed peer and a missing port are errors") {
  auto pty = std::make_unique<Pty>();
  SpSerial port(pty->slave_path());
  pty.reset();  // the master (and the pty's own slave handle) close: the line is gone
  std::uint8_t buf[16] = {1, 2, 3};
  CHECK_THROWS_AS(port.read(buf, sizeof buf, 200), std::runtime_error);
  CHECK_THROWS_WITH_AS(port.write(buf, 3), doctest::Contains("libserialport: write"), std::runtime_error);

  CHECK_THROWS_AS(SpSerial("/dev/ttyGEOJCBB_NO_SUCH_PORT"), std::runtime_error);
  CHECK_THROWS_AS(SpSerial("not-a-device-path"), std::runtime_error);
  CHECK_THROWS_AS(open_transport("/dev/ttyGEOJCBB_NO_SUCH_PORT", 115200), std::runtime_error);
  Pty other;
  CHECK_THROWS_AS(SpSerial(other.slave_path(), 0), std::runtime_error);
}

TEST_CASE("open_transport: termios for ptys, libserialport otherwise, or as forced") {
  CHECK(parse_transport_kind("auto") == TransportKind::kAuto);
  CHECK(parse_transport_kind("termios") == TransportKind::kTermios);
  CHECK(parse_transport_kind("libserialport") == TransportKind::kLibserialport);
  CHECK_THROWS_AS(parse_transport_kind("usb"), std::invalid_argument);
  for (TransportKind k : {TransportKind::kAuto, TransportKind::kTermios, TransportKind::kLibserialport}) {
    CHECK(parse_transport_kind(transport_kind_name(k)) == k);
  }
  CHECK(resolve_transport_kind("/dev/pts/7") == TransportKind::kTermios);
  CHECK(resolve_transport_kind("/dev/ttyUSB0") == TransportKind::kLibserialport);
  CHECK(resolve_transport_kind("/dev/ttyACM0", TransportKind::kTermios) == TransportKind::kTermios);
  CHECK(resolve_transport_kind("/dev/pts/7", TransportKind::kLibserialport) == TransportKind::kLibserialport);

  Pty pty;
  // A symlink to a pty (as socat makes) is still a pty.
  const std::filesystem::path link =
      std::filesystem::temp_directory_path() / ("geojcbb_pty_link_" + std::to_string(getpid()));
  std::filesystem::remove(link);
  std::filesystem::create_symlink(pty.slave_path(), link);
  CHECK(resolve_transport_kind(link.string()) == TransportKind::kTermios);
  std::filesystem::remove(link);

  std::unique_ptr<Transport> a = open_transport(pty.slave_path(), 115200);
  CHECK(dynamic_cast<PosixSerial*>(a.get()) != nullptr);
  std::unique_ptr<Transport> b = open_transport(pty.slave_path(), 115200, TransportKind::kLibserialport);
  CHECK(dynamic_cast<SpSerial*>(b.get()) != nullptr);
  const std::uint8_t x[] = {0xC0, 0xFF, 0xEE};
  b->write(x, sizeof x);
  CHECK(read_n(pty, sizeof x) == std::vector<std::uint8_t>(x, x + sizeof x));
}

TEST_CASE("list_ports runs (the list may be empty on a machine without serial ports)") {
  std::vector<PortInfo> ports;
  REQUIRE_NOTHROW(ports = list_ports());
  MESSAGE(ports.size() << " serial port(s) found");
  for (const PortInfo& p : ports) {
    CAPTURE(port_line(p));
    CHECK(p.name.rfind("/dev/", 0) == 0);
    CHECK((p.transport == "native" || p.transport == "usb" || p.transport == "bluetooth"));
    CHECK(port_line(p).rfind(p.name, 0) == 0);
    CHECK(p.name.rfind("/dev/pts/", 0) != 0);
  }
  PortInfo usb;
  usb.name = "/dev/ttyUSB0";
  usb.transport = "usb";
  usb.usb_vid = 0x0403;
  usb.usb_pid = 0x6001;
  usb.usb_serial = "A50285BI";
  usb.description = "FT232R USB UART";
  CHECK(port_line(usb) == "/dev/ttyUSB0  usb 0403:6001 serial A50285BI  FT232R USB UART");
}

TEST_CASE("a LinkClient session over SpSerial equals the same session over the termios transport") {
  const Session termios = session(false);
  const Session sp = session(true);
  CHECK(sp.capabilities == termios.capabilities);
  REQUIRE(termios.replies.size() >= 20);  // at least 10 scans, each ASSOC_RESULT + POSE
  MESSAGE("session: " << termios.run.scans << " scans, " << termios.stats.frames_ok << " frames to the device");
  CHECK(sp.run.scans == termios.run.scans);
  CHECK(sp.replies.size() == termios.replies.size());
  long differing = 0;
  for (std::size_t i = 0; i < std::min(sp.replies.size(), termios.replies.size()); ++i) {
    differing += sp.replies[i] != termios.replies[i];
  }
  CHECK(differing == 0);
  CHECK(sp.run.score.tp == termios.run.score.tp);
  CHECK(sp.run.score.tn == termios.run.score.tn);
  CHECK(sp.run.score.fp == termios.run.score.fp);
  CHECK(sp.run.score.fn == termios.run.score.fn);
  CHECK(sp.stats.frames_ok == termios.stats.frames_ok);
  CHECK(sp.stats.scans == termios.stats.scans);
  CHECK(sp.stats.scans == static_cast<std::uint32_t>(termios.run.scans));
  CHECK(sp.stats.bad_crc + sp.stats.bad_length + sp.stats.overrun + sp.stats.invalid_field == 0u);
}
