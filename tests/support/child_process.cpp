#include "tests/support/child_process.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>

extern char** environ;

namespace ceilpose::test {
namespace {

using Clock = std::chrono::steady_clock;

// Without a pidfd the exit is noticed by polling waitpid this often.
constexpr int kExitPollMs = 10;
// One drain reads at most this much, so a child that writes without pause
// cannot keep the caller reading past its deadline.
constexpr size_t kMaxReadPerDrainBytes = size_t{1} << 20;
constexpr int kPipeBytes = 1 << 20;

int ms_until(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::max<int64_t>(0, left.count()));
}

Clock::time_point deadline_after(int timeout_ms) {
  return Clock::now() + std::chrono::milliseconds(std::max(0, timeout_ms));
}

// This process's environment with `changes` applied (empty value: removed).
std::vector<std::string> child_environment(const std::map<std::string, std::string>& changes) {
  std::map<std::string, std::string> merged;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string kv(*e);
    const size_t eq = kv.find('=');
    if (eq != std::string::npos) merged[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  for (const auto& [name, value] : changes) {
    if (value.empty()) {
      merged.erase(name);
    } else {
      merged[name] = value;
    }
  }
  std::vector<std::string> env;
  for (const auto& [name, value] : merged) env.push_back(name + "=" + value);
  return env;
}

std::vector<char*> c_strings(std::vector<std::string>& text) {
  std::vector<char*> out;
  for (auto& s : text) out.push_back(s.data());
  out.push_back(nullptr);
  return out;
}

// A pipe whose read end (fds[0]) never blocks; both ends close on exec, the
// child gets the write end through dup2.
bool make_pipe(int fds[2]) {
  if (pipe2(fds, O_CLOEXEC) != 0) return false;
  fcntl(fds[0], F_SETFL, fcntl(fds[0], F_GETFL) | O_NONBLOCK);
  // Output is read only while the test calls in here; a larger pipe (best
  // effort, 1 MiB is the unprivileged limit) lets a chatty daemon log on
  // while the test waits on something else.
  fcntl(fds[1], F_SETPIPE_SZ, kPipeBytes);
  return true;
}

// Through syscall(): Debian 12's <sys/pidfd.h> declares pidfd_open without
// C linkage, so C++ cannot link against it.
int open_pidfd(pid_t pid) { return static_cast<int>(syscall(SYS_pidfd_open, pid, 0)); }

void close_fd(int& fd) {
  if (fd >= 0) close(fd);
  fd = -1;
}

}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv, ChildOptions options)
    : max_output_bytes_(options.max_output_bytes) {
  // A child that never started reads as ended, so every wait returns at once.
  exit_ = ExitStatus{};
  if (argv.empty()) {
    start_error_ = "cannot start a child process: empty argv";
    return;
  }
  int out[2] = {-1, -1};
  int err[2] = {-1, -1};
  if (!make_pipe(out) || (options.capture_stderr && !make_pipe(err))) {
    start_error_ = "cannot start " + argv[0] + ": pipe: " + std::strerror(errno);
    for (int* fd : {&out[0], &out[1], &err[0], &err[1]}) close_fd(*fd);
    return;
  }
  std::vector<std::string> args_text = argv;
  std::vector<std::string> env_text = child_environment(options.env);
  std::vector<char*> args = c_strings(args_text);
  std::vector<char*> env = c_strings(env_text);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, options.stdout_fd >= 0 ? options.stdout_fd : out[1],
                                   STDOUT_FILENO);
  if (err[1] >= 0) posix_spawn_file_actions_adddup2(&actions, err[1], STDERR_FILENO);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  close_fd(out[1]);
  close_fd(err[1]);
  out_.fd = out[0];
  err_.fd = err[0];
  if (rc != 0) {
    start_error_ = "cannot start " + argv[0] + ": " + std::strerror(rc);
    close_fd(out_.fd);
    close_fd(err_.fd);
    return;
  }
  pid_ = pid;
  exit_.reset();
  pidfd_ = open_pidfd(pid_);
}

ChildProcess::~ChildProcess() {
  if (!exit_) kill();
  close_fd(pidfd_);
  close_fd(out_.fd);
  close_fd(err_.fd);
}

void ChildProcess::signal(int sig) {
  if (pid_ > 0 && !exit_) ::kill(pid_, sig);
}

bool ChildProcess::running() { return !wait(0).has_value(); }

std::optional<ExitStatus> ChildProcess::wait(int timeout_ms) {
  const auto deadline = deadline_after(timeout_ms);
  for (;;) {
    if (reap(false)) return exit_;
    const int left_ms = ms_until(deadline);
    if (left_ms <= 0) return std::nullopt;
    pump(left_ms);
  }
}

int ChildProcess::wait_exit(int timeout_ms) {
  if (const auto e = wait(timeout_ms)) return e->code;
  kill();
  return -1;
}

ExitStatus ChildProcess::terminate(int grace_ms) {
  signal(SIGTERM);
  if (const auto e = wait(grace_ms)) return *e;
  return kill();
}

ExitStatus ChildProcess::kill() {
  signal(SIGKILL);
  reap(true);
  return *exit_;
}

const std::string& ChildProcess::read_until(const std::string& needle, int timeout_ms) {
  return read_until(out_, needle, timeout_ms);
}

const std::string& ChildProcess::read_error_until(const std::string& needle, int timeout_ms) {
  return read_until(err_, needle, timeout_ms);
}

const std::string& ChildProcess::read_until(Stream& s, const std::string& needle, int timeout_ms) {
  const auto deadline = deadline_after(timeout_ms);
  read_available(s);
  while (s.text.find(needle) == std::string::npos && s.fd >= 0) {
    // Once the child has ended, what it wrote is all in the pipe already: a
    // grandchild holding the pipe open must not keep this waiting for EOF.
    if (reap(false)) break;
    const int left_ms = ms_until(deadline);
    if (left_ms <= 0) break;
    pump(left_ms);
  }
  return s.text;
}

const std::string& ChildProcess::output() {
  read_available(out_);
  return out_.text;
}

const std::string& ChildProcess::error_output() {
  read_available(err_);
  return err_.text;
}

void ChildProcess::pump(int timeout_ms) {
  pollfd fds[3] = {{out_.fd, POLLIN, 0}, {err_.fd, POLLIN, 0}, {pidfd_, POLLIN, 0}};
  const int wait_ms = pidfd_ >= 0 ? timeout_ms : std::min(timeout_ms, kExitPollMs);
  if (poll(fds, 3, wait_ms) <= 0) return;
  read_available(out_);
  read_available(err_);
}

void ChildProcess::read_available(Stream& s) {
  char buf[16384];
  size_t read_bytes = 0;
  while (s.fd >= 0 && read_bytes < kMaxReadPerDrainBytes) {
    const ssize_t n = read(s.fd, buf, sizeof buf);
    if (n > 0) {
      read_bytes += static_cast<size_t>(n);
      const size_t room = max_output_bytes_ - std::min(max_output_bytes_, s.text.size());
      s.text.append(buf, std::min(room, static_cast<size_t>(n)));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      if (n == 0 || errno != EAGAIN) close_fd(s.fd);  // EOF, or a pipe that cannot be read
      return;
    }
  }
}

bool ChildProcess::reap(bool block) {
  if (exit_) return true;
  int status = 0;
  pid_t r = -1;
  do {
    r = waitpid(pid_, &status, block ? 0 : WNOHANG);
  } while (r < 0 && errno == EINTR);
  if (r == 0) return false;
  ExitStatus e;
  // r < 0 (ECHILD): reaped elsewhere; reported as ended without a status
  // rather than waited for forever.
  if (r == pid_ && WIFEXITED(status)) {
    e.exited = true;
    e.code = WEXITSTATUS(status);
  } else if (r == pid_ && WIFSIGNALED(status)) {
    e.signal = WTERMSIG(status);
  }
  exit_ = e;
  close_fd(pidfd_);
  // Everything the child wrote is in the pipes now; take it before returning.
  read_available(out_);
  read_available(err_);
  return true;
}

RunOutput run_to_end(const std::vector<std::string>& argv, int timeout_ms, int stdout_fd) {
  ChildOptions options;
  options.capture_stderr = true;
  options.stdout_fd = stdout_fd;
  ChildProcess child(argv, options);
  RunOutput result;
  if (!child.started()) {
    result.failure = child.start_error();
    return result;
  }
  if (const auto e = child.wait(timeout_ms)) {
    result.exit_code = e->code;
  } else {
    child.kill();
    result.failure = argv[0] + " still running after " + std::to_string(timeout_ms) + " ms, killed";
  }
  result.out = child.output();
  result.err = child.error_output();
  return result;
}

}  // namespace ceilpose::test
