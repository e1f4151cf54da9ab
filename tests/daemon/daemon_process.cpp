#include "tests/daemon/daemon_process.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "ipc/shm/shm_fleet_writer.h"
#include "ipc/shm/shm_pose_writer.h"
#include "tests/support/temp_file.h"

namespace ceilpose::test {
namespace {

std::atomic<int> g_counter{0};

ChildOptions daemon_options(const std::map<std::string, std::string>& env, int stdout_fd) {
  ChildOptions options;
  options.capture_stderr = true;
  options.stdout_fd = stdout_fd;
  // A test never inherits the systemd protocol from whoever runs ctest.
  options.env = {{"NOTIFY_SOCKET", ""}, {"WATCHDOG_USEC", ""}, {"WATCHDOG_PID", ""}};
  for (const auto& [name, value] : env) options.env[name] = value;
  return options;
}

std::vector<std::string> daemon_argv(const std::vector<std::string>& args) {
  std::vector<std::string> argv{CEILPOSED_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

}  // namespace

NotifySocket::NotifySocket() {
  // sun_path is short (108 bytes): keep the path under /tmp.
  path_ = "/tmp/ceilposed-notify-" + std::to_string(getpid()) + "-" +
          std::to_string(g_counter.fetch_add(1));
  unlink(path_.c_str());
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path_.c_str(), sizeof(addr.sun_path) - 1);
  if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0)
    throw std::runtime_error("bind " + path_ + ": " + std::strerror(errno));
}

NotifySocket::~NotifySocket() {
  if (fd_ >= 0) close(fd_);
  unlink(path_.c_str());
}

std::optional<std::string> NotifySocket::receive(int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  if (poll(&p, 1, timeout_ms) <= 0) return std::nullopt;
  char buf[4096];
  const ssize_t n = recv(fd_, buf, sizeof(buf), 0);
  if (n < 0) return std::nullopt;
  return std::string(buf, static_cast<size_t>(n));
}

bool NotifySocket::wait_for(const std::string& line, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    auto msg = receive(static_cast<int>(std::max<int64_t>(1, left.count())));
    if (!msg) continue;
    std::istringstream lines(*msg);
    for (std::string l; std::getline(lines, l);)
      if (l == line) return true;
  }
  return false;
}

DaemonProcess::DaemonProcess(const std::vector<std::string>& args,
                             const std::map<std::string, std::string>& env, int stdout_fd)
    : ChildProcess(daemon_argv(args), daemon_options(env, stdout_fd)) {
  if (!started()) throw std::runtime_error(start_error());
}

RunResult run_daemon(const std::vector<std::string>& args, int timeout_ms,
                     const std::map<std::string, std::string>& env) {
  DaemonProcess p(args, env);
  RunResult r;
  if (const auto e = p.wait(timeout_ms)) {
    r.exit = *e;
  } else {
    r.exit = p.kill();
    ADD_FAILURE() << "ceilposed did not end within " << timeout_ms << " ms";
  }
  r.out = p.output();
  r.err = p.error_output();
  return r;
}

std::string unique_shm_name() {
  return "/ceilpose-test-" + std::to_string(getpid()) + "-" +
         std::to_string(g_counter.fetch_add(1));
}

bool shm_exists(const std::string& name) {
  struct stat st {};
  return stat(("/dev/shm" + name).c_str(), &st) == 0;
}

void remove_daemon_segments(const std::string& shm) {
  (void)ShmPoseWriter::remove(shm);
  (void)ShmFleetWriter::remove(fleet_segment_name(shm));
}

std::string write_temp_file(const std::string& stem, const std::string& text) {
  return write_temp("ceilposed", std::to_string(g_counter.fetch_add(1)) + "-" + stem, text);
}

}  // namespace ceilpose::test
