#include "geojcbb_host/device_process.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <thread>
#include <vector>
#include <algorithm>

namespace geojcbb::host {

DeviceProcess::DeviceProcess(const std::string& program) {
  // "PROG ARG ...": the program and its own arguments, split at spaces; --pty is added.
  std::vector<std::string> words;
  for (std::size_t i = 0; i < program.size();) {
    const std::size_t j = std::min(program.find(' ', i), program.size());
    if (j > i) words.push_back(program.substr(i, j - i));
    i = j + 1;
  }
  if (words.empty()) throw std::runtime_error("no device program given");
  words.emplace_back("--pty");
  std::vector<char*> argv;
  argv.reserve(words.size() + 1);
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw std::runtime_error("fork failed");
  }
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    close(fds[0]);
    close(fds[1]);
    execv(argv[0], argv.data());
    _exit(127);
  }
  pid_ = pid;
  close(fds[1]);
  FILE* f = fdopen(fds[0], "r");
  char line[512] = {0};
  const bool got = f != nullptr && std::fgets(line, sizeof line, f) != nullptr;
  if (f != nullptr) {
    std::fclose(f);
  } else {
    close(fds[0]);
  }
  const std::string s = got ? line : "";
  if (s.rfind("pty: ", 0) != 0) {
    kill(pid_, SIGTERM);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
    throw std::runtime_error("device did not report its pty: " + program);
  }
  port_ = s.substr(5);
  while (!port_.empty() && (port_.back() == '\n' || port_.back() == '\r')) port_.pop_back();
}

DeviceProcess::~DeviceProcess() {
  if (pid_ <= 0) return;
  kill(pid_, SIGTERM);
  waitpid(pid_, nullptr, 0);
}

int DeviceProcess::wait_exit(int timeout_ms) {
  if (pid_ <= 0) return -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      pid_ = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    if (r < 0 || std::chrono::steady_clock::now() >= deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// ---------------------------------------------------------------------------------------------

DeviceLink::DeviceLink(const LinkCli& cli, bool start_device) : port_(cli.port) {
  if (start_device) {
    process_ = std::make_unique<DeviceProcess>(cli.device);
    port_ = process_->port();
  }
  SessionOptions so;
  const std::string port = port_;
  const TransportKind kind = parse_transport_kind(cli.transport);
  const int baud = cli.baud;
  so.open = [port, baud, kind] { return open_transport(port, baud, kind); };
  so.timeout_ms = cli.timeout_ms;
  so.reconnect_ms = cli.reconnect_ms;
  so.max_restarts = cli.max_restarts;
  session_ = std::make_unique<LinkSession>(so);
}

DeviceLink::~DeviceLink() = default;

std::string DeviceLink::describe() {
  const proto::Capabilities& c = session_->capabilities();
  char b[256];
  std::snprintf(b, sizeof b,
                "device on %s: boot id %08x, %d-byte scalars, up to %u observations, %u landmarks; schema %08x",
                port_.c_str(), c.boot_id, c.scalar_bytes, c.max_observations, c.max_landmarks, c.schema_hash);
  return b;
}

int DeviceLink::shut_down() {
  if (!process_) return 0;
  std::fflush(stdout);  // the device's last words (stderr) come after ours
  session_->shutdown(0);
  return process_->wait_exit(5000);
}

}  // namespace geojcbb::host
