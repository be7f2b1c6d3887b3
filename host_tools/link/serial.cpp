#include "geojcbb_host/serial.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

namespace geojcbb::host {

namespace {
[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what + ": " + std::strerror(errno)); }

speed_t speed_of(int baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    default: throw std::runtime_error("unsupported baud rate " + std::to_string(baud));
  }
}

void make_raw(int fd, int baud, const std::string& path) {
  termios t{};
  if (tcgetattr(fd, &t) != 0) fail("tcgetattr " + path);
  cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  cfsetispeed(&t, speed_of(baud));
  cfsetospeed(&t, speed_of(baud));
  if (tcsetattr(fd, TCSANOW, &t) != 0) fail("tcsetattr " + path);
}

std::size_t read_fd(int fd, std::uint8_t* p, std::size_t n, int timeout_ms, const std::string& path) {
  pollfd pfd{fd, POLLIN, 0};
  const int r = poll(&pfd, 1, timeout_ms);
  if (r < 0) {
    if (errno == EINTR) return 0;
    fail("poll " + path);
  }
  if (r == 0) return 0;
  const ssize_t got = ::read(fd, p, n);
  if (got < 0) {
    if (errno == EAGAIN || errno == EINTR) return 0;
    fail("read " + path);
  }
  if (got == 0 && (pfd.revents & POLLHUP)) throw std::runtime_error(path + ": closed");
  return static_cast<std::size_t>(got);
}

void write_fd(int fd, const std::uint8_t* p, std::size_t n, const std::string& path) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN) {
        pollfd pfd{fd, POLLOUT, 0};
        poll(&pfd, 1, 100);
        continue;
      }
      fail("write " + path);
    }
    p += w;
    n -= static_cast<std::size_t>(w);
  }
}
}  // namespace

PosixSerial::PosixSerial(const std::string& path, int baud) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) fail("open " + path);
  try {
    make_raw(fd_, baud, path);
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

PosixSerial::~PosixSerial() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t PosixSerial::read(std::uint8_t* p, std::size_t n, int timeout_ms) {
  return read_fd(fd_, p, n, timeout_ms, path_);
}

void PosixSerial::write(const std::uint8_t* p, std::size_t n) { write_fd(fd_, p, n, path_); }

Pty::Pty() {
  master_ = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master_ < 0) fail("posix_openpt");
  if (grantpt(master_) != 0 || unlockpt(master_) != 0) fail("grantpt/unlockpt");
  const char* name = ptsname(master_);
  if (name == nullptr) fail("ptsname");
  slave_ = name;
  make_raw(master_, 115200, "pty master");
  slave_keep_ = ::open(slave_.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (slave_keep_ < 0) fail("open " + slave_);
  make_raw(slave_keep_, 115200, slave_);
  const int fl = fcntl(master_, F_GETFL);
  fcntl(master_, F_SETFL, fl | O_NONBLOCK);
}

Pty::~Pty() {
  if (slave_keep_ >= 0) ::close(slave_keep_);
  if (master_ >= 0) ::close(master_);
}

std::size_t Pty::read(std::uint8_t* p, std::size_t n, int timeout_ms) {
  return read_fd(master_, p, n, timeout_ms, "pty master");
}

void Pty::write(const std::uint8_t* p, std::size_t n) { write_fd(master_, p, n, "pty master"); }

}  // namespace geojcbb::host
