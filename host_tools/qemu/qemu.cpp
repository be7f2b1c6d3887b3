#include "geojcbb_host/qemu.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

namespace geojcbb::host {

namespace {
using Clock = std::chrono::steady_clock;
int ms_left(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  return left > 0 ? static_cast<int>(left) : 0;
}
}  // namespace

QemuMachine::QemuMachine(const QemuOptions& o) {
  try {
    start(o);
  } catch (...) {
    cleanup();  // the destructor does not run for a constructor that throws: QEMU (halted) would stay
    throw;
  }
}

void QemuMachine::start(const QemuOptions& o) {
  char dir[] = "/tmp/geojcbb-qemu-XXXXXX";
  if (mkdtemp(dir) == nullptr) throw std::runtime_error("mkdtemp failed");
  socket_path_ = std::string(dir) + "/qmp.sock";
  std::vector<std::string> args = {o.qemu,
                                   "-M",
                                   o.machine,
                                   "-nodefaults",
                                   "-display",
                                   "none",
                                   "-nic",
                                   "none",
                                   "-semihosting-config",
                                   "enable=on,target=native",
                                   "-S",
                                   "-serial",
                                   "pty",
                                   "-qmp",
                                   "unix:" + socket_path_ + ",server=on,wait=off",
                                   "-kernel",
                                   o.elf};
  if (o.icount) {
    args.push_back("-icount");
    args.push_back("shift=0");
  }
  for (const std::string& a : args) command_ += (command_.empty() ? "" : " ") + a;
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    std::vector<char*> argv;
    argv.reserve(args.size() + 1);
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  // QMP: the socket appears once QEMU has parsed its options; connect as soon as it accepts.
  const auto deadline = Clock::now() + std::chrono::milliseconds(o.start_timeout_ms);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, socket_path_.c_str(), sizeof addr.sun_path - 1);
  while (true) {
    qmp_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (qmp_fd_ < 0) throw std::runtime_error("socket failed");
    if (connect(qmp_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) break;
    close(qmp_fd_);
    qmp_fd_ = -1;
    int st = 0;
    if (waitpid(pid_, &st, WNOHANG) == pid_) {
      exited_ = true;
      pid_ = -1;
      throw std::runtime_error("QEMU exited at start (status " + std::to_string(WEXITSTATUS(st)) + "): " + command_);
    }
    if (ms_left(deadline) == 0) throw std::runtime_error("QEMU's QMP socket did not open: " + command_);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // polling a condition, with a deadline
  }
  const std::string greeting = read_line(ms_left(deadline) + 1);
  if (greeting.find("\"QMP\"") == std::string::npos) throw std::runtime_error("no QMP greeting: " + greeting);
  qmp(R"({"execute": "qmp_capabilities"})");
  const nlohmann::json chardevs = nlohmann::json::parse(qmp(R"({"execute": "query-chardev"})"));
  for (const auto& c : chardevs.at("return")) {
    const std::string file = c.value("filename", "");
    if (c.value("label", "") == "serial0" && file.rfind("pty:", 0) == 0) pty_ = file.substr(4);
  }
  if (pty_.empty()) throw std::runtime_error("QMP query-chardev lists no pty for serial0: " + chardevs.dump());
}

QemuMachine::~QemuMachine() { cleanup(); }

void QemuMachine::cleanup() {
  if (qmp_fd_ >= 0) close(qmp_fd_);
  qmp_fd_ = -1;
  if (pid_ > 0 && !exited_) {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    exited_ = true;
  }
  if (!socket_path_.empty()) {
    unlink(socket_path_.c_str());
    const std::size_t slash = socket_path_.rfind('/');
    if (slash != std::string::npos) rmdir(socket_path_.substr(0, slash).c_str());
    socket_path_.clear();
  }
}

std::string QemuMachine::read_line(int timeout_ms) {
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (true) {
    const std::size_t nl = buffer_.find('\n');
    if (nl != std::string::npos) {
      std::string line = buffer_.substr(0, nl);
      buffer_.erase(0, nl + 1);
      return line;
    }
    pollfd p{qmp_fd_, POLLIN, 0};
    const int r = poll(&p, 1, ms_left(deadline));
    if (r == 0) throw std::runtime_error("QMP: no reply in time");
    if (r < 0 && errno == EINTR) continue;
    char buf[4096];
    const ssize_t n = ::read(qmp_fd_, buf, sizeof buf);
    if (n <= 0) throw std::runtime_error("QMP: connection closed");
    buffer_.append(buf, static_cast<std::size_t>(n));
  }
}

std::string QemuMachine::qmp(const std::string& json) {
  const std::string line = json + "\n";
  if (::write(qmp_fd_, line.data(), line.size()) != static_cast<ssize_t>(line.size())) {
    throw std::runtime_error("QMP: write failed");
  }
  while (true) {  // events may come first; the reply carries "return" or "error"
    std::string reply = read_line(5000);
    if (reply.find("\"return\"") != std::string::npos) return reply;
    if (reply.find("\"error\"") != std::string::npos) throw std::runtime_error("QMP error: " + reply);
  }
}

void QemuMachine::cont() { qmp(R"({"execute": "cont"})"); }

int QemuMachine::wait_exit(int timeout_ms) {
  if (exited_) return status_;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (true) {
    int st = 0;
    const pid_t r = waitpid(pid_, &st, WNOHANG);
    if (r == pid_) {
      exited_ = true;
      status_ = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
      return status_;
    }
    if (ms_left(deadline) == 0) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // polling a condition, with a deadline
  }
}

}  // namespace geojcbb::host
