#include "tests/daemon/daemon_process.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

extern char** environ;

namespace ceilpose::test {
namespace {

std::atomic<int> g_counter{0};

std::string temp_path(const std::string& stem) {
  return ::testing::TempDir() + "ceilposed-" + std::to_string(getpid()) + "-" +
         std::to_string(g_counter.fetch_add(1)) + "-" + stem;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
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
                             const std::map<std::string, std::string>& env) {
  out_path_ = temp_path("stdout");
  err_path_ = temp_path("stderr");
  std::vector<std::string> argv_s{CEILPOSED_PATH};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);

  std::map<std::string, std::string> merged;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string kv(*e);
    const size_t eq = kv.find('=');
    if (eq != std::string::npos) merged[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  // A test never inherits the systemd protocol from whoever runs ctest.
  merged.erase("NOTIFY_SOCKET");
  merged.erase("WATCHDOG_USEC");
  merged.erase("WATCHDOG_PID");
  for (const auto& [k, v] : env) {
    if (v.empty()) {
      merged.erase(k);
    } else {
      merged[k] = v;
    }
  }
  std::vector<std::string> env_s;
  for (const auto& [k, v] : merged) env_s.push_back(k + "=" + v);
  std::vector<char*> envp;
  for (auto& e : env_s) envp.push_back(e.data());
  envp.push_back(nullptr);

  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, out_path_.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, err_path_.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int r = posix_spawn(&pid_, argv[0], &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  if (r != 0) throw std::runtime_error(std::string("posix_spawn ceilposed: ") + std::strerror(r));
}

DaemonProcess::~DaemonProcess() {
  if (running()) {
    kill(pid_, SIGKILL);
    wait(5000);
  }
  unlink(out_path_.c_str());
  unlink(err_path_.c_str());
}

void DaemonProcess::signal(int sig) { kill(pid_, sig); }

bool DaemonProcess::running() {
  if (exit_) return false;
  return !wait(0).has_value();
}

std::optional<Exit> DaemonProcess::wait(int timeout_ms) {
  if (exit_) return exit_;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      Exit e;
      e.exited = WIFEXITED(status);
      e.code = e.exited ? WEXITSTATUS(status) : -1;
      e.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
      exit_ = e;
      return exit_;
    }
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

std::string DaemonProcess::out() const { return read_file(out_path_); }
std::string DaemonProcess::err() const { return read_file(err_path_); }

RunResult run_daemon(const std::vector<std::string>& args, int timeout_ms,
                     const std::map<std::string, std::string>& env) {
  DaemonProcess p(args, env);
  RunResult r;
  auto e = p.wait(timeout_ms);
  if (!e) {
    p.signal(SIGKILL);
    e = p.wait(5000);
    ADD_FAILURE() << "ceilposed did not end within " << timeout_ms << " ms";
  }
  r.exit = e.value_or(Exit{});
  r.out = p.out();
  r.err = p.err();
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

std::string write_temp_file(const std::string& stem, const std::string& text) {
  const std::string path = temp_path(stem);
  std::ofstream(path) << text;
  return path;
}

}  // namespace ceilpose::test
