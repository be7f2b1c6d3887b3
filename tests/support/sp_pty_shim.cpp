// The pty shim for libserialport (sp_pty_shim.hpp says what and why). Test-only.
#ifdef _FORTIFY_SOURCE
#undef _FORTIFY_SOURCE  // readlink must be a plain function here, not a fortify wrapper
#endif

#include "support/sp_pty_shim.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>

namespace {

std::atomic<bool> g_sysfs{true};
std::atomic<bool> g_modem{true};
std::atomic<long> g_sysfs_lookups{0};
std::atomic<long> g_modem_get{0};
std::atomic<long> g_modem_set{0};

// The pty's sysfs name as libserialport 0.1.1 builds it ("/sys/class/tty/" + "pts/N"), and as
// later upstream versions do (the slash escaped: "pts!N").
constexpr char kPtsDir[] = "/sys/class/tty/pts/";
constexpr char kPtsEscaped[] = "/sys/class/tty/pts!";

const char* pty_sysfs_number(const char* path) {
  if (!g_sysfs.load()) return nullptr;
  if (std::strncmp(path, kPtsDir, sizeof kPtsDir - 1) == 0) return path + sizeof kPtsDir - 1;
  if (std::strncmp(path, kPtsEscaped, sizeof kPtsEscaped - 1) == 0) return path + sizeof kPtsEscaped - 1;
  return nullptr;
}

// Unix98 pty slaves: character devices with majors 136..143 (the kernel's devices.txt).
bool pty_slave(int fd, dev_t& rdev) {
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISCHR(st.st_mode)) return false;
  const unsigned m = major(st.st_rdev);
  rdev = st.st_rdev;
  return m >= 136 && m <= 143;
}

// The modem lines of each pty the shim has seen, by device number. A new pty starts with DTR and
// RTS asserted, as a UART after open.
struct Lines {
  std::mutex mu;
  std::map<dev_t, int> bits;
};
Lines& lines() {
  static Lines l;  // constructed on first use: ioctl may be called before this file's statics
  return l;
}

template <class F>
F next(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

using IoctlFn = int (*)(int, unsigned long, ...);
using ReadlinkFn = ssize_t (*)(const char*, char*, size_t);
using LstatFn = int (*)(const char*, struct stat*);

int forward_ioctl(int fd, unsigned long request, void* arg) {
  static const IoctlFn real = next<IoctlFn>("ioctl");
  if (real != nullptr) return real(fd, request, arg);
  return static_cast<int>(syscall(SYS_ioctl, fd, request, arg));
}

int fake_link_stat(struct stat* buf) {
  std::memset(buf, 0, sizeof *buf);
  buf->st_mode = S_IFLNK | 0777;
  buf->st_nlink = 1;
  g_sysfs_lookups.fetch_add(1);
  return 0;
}

int forward_lstat(const char* path, struct stat* buf) {
  static const LstatFn real = next<LstatFn>("lstat");
  if (real != nullptr) return real(path, buf);
  return fstatat(AT_FDCWD, path, buf, AT_SYMLINK_NOFOLLOW);
}

}  // namespace

extern "C" {

// Interposers keep glibc's reserved names, and lstat's parameters <sys/stat.h>'s names, so that the
// definitions match the declarations they replace.
// NOLINTBEGIN(bugprone-reserved-identifier)

// glibc's old stat entry point, which libserialport 0.1.1 (Debian 12) calls for lstat().
int __lxstat(int ver, const char* path, struct stat* buf);
int __lxstat(int /*ver*/, const char* path, struct stat* buf) {
  if (path != nullptr && pty_sysfs_number(path) != nullptr) return fake_link_stat(buf);
  return forward_lstat(path, buf);  // x86-64: _STAT_VER's layout is struct stat
}

int lstat(const char* __restrict __file, struct stat* __restrict __buf) noexcept {
  if (pty_sysfs_number(__file) != nullptr) return fake_link_stat(__buf);
  return forward_lstat(__file, __buf);
}
// NOLINTEND(bugprone-reserved-identifier)

ssize_t readlink(const char* __restrict path, char* __restrict buf, size_t len) noexcept {
  if (const char* n = pty_sysfs_number(path)) {
    // What sysfs would hold for a virtual tty: not "usb" or "bluetooth", so a native port.
    char target[128];
    const int w = std::snprintf(target, sizeof target, "../../devices/virtual/tty/pts/%s", n);
    const size_t k = w < 0 ? 0 : std::min(static_cast<size_t>(w), len);
    std::memcpy(buf, target, k);  // readlink does not terminate
    g_sysfs_lookups.fetch_add(1);
    return static_cast<ssize_t>(k);
  }
  static const ReadlinkFn real = next<ReadlinkFn>("readlink");
  if (real != nullptr) return real(path, buf, len);
  return syscall(SYS_readlink, path, buf, len);
}

int ioctl(int fd, unsigned long request, ...) noexcept {
  va_list ap;
  va_start(ap, request);
  void* arg = va_arg(ap, void*);
  va_end(ap);
  const bool modem = request == TIOCMGET || request == TIOCMSET || request == TIOCMBIS || request == TIOCMBIC;
  dev_t rdev = 0;
  if (!modem || !g_modem.load() || arg == nullptr || !pty_slave(fd, rdev)) return forward_ioctl(fd, request, arg);
  int* word = static_cast<int*>(arg);
  Lines& l = lines();
  const std::lock_guard<std::mutex> lock(l.mu);
  auto it = l.bits.emplace(rdev, TIOCM_DTR | TIOCM_RTS).first;
  switch (request) {
    case TIOCMGET:
      *word = it->second;
      g_modem_get.fetch_add(1);
      return 0;
    case TIOCMSET: it->second = *word; break;
    case TIOCMBIS: it->second |= *word; break;
    default:  // TIOCMBIC
      it->second &= ~*word;
      break;
  }
  g_modem_set.fetch_add(1);
  return 0;
}

}  // extern "C"

namespace geojcbb::test::sp_pty_shim {

void set_sysfs(bool on) { g_sysfs = on; }
void set_modem_lines(bool on) { g_modem = on; }

Counts counts() {
  Counts c;
  c.sysfs_lookups = g_sysfs_lookups.load();
  c.modem_get = g_modem_get.load();
  c.modem_set = g_modem_set.load();
  return c;
}

int modem_lines(const char* path) {
  struct stat st;
  if (stat(path, &st) != 0) return -1;
  Lines& l = lines();
  const std::lock_guard<std::mutex> lock(l.mu);
  const auto it = l.bits.find(st.st_rdev);
  return it == l.bits.end() ? -1 : it->second;
}

}  // namespace geojcbb::test::sp_pty_shim
