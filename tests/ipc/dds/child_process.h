#pragma once
// A child process for cross-process DDS tests: spawned with its stdout on a
// pipe, read with bounded waits, and always terminated and reaped.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "core/clock.h"

extern char** environ;

namespace ceilpose::test {

class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& argv) {
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    out_fd_ = fds[0];
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) close(out_fd_);
  }

  bool started() const { return pid_ > 0; }

  // Reads stdout until `needle` appears, EOF, or timeout; returns all read so far.
  std::string read_until(const std::string& needle, int64_t timeout_ms) {
    const int64_t deadline_ns = monotonic_ns() + timeout_ms * 1'000'000;
    while (output_.find(needle) == std::string::npos) {
      const int64_t left_ms = (deadline_ns - monotonic_ns()) / 1'000'000;
      if (left_ms <= 0 || !read_some(static_cast<int>(left_ms))) break;
    }
    return output_;
  }

  // Reads to EOF and waits for the exit, killing the child at the deadline.
  // Returns the exit status, or -1 if it had to be killed or died of a signal.
  int wait_exit(int64_t timeout_ms) {
    const int64_t deadline_ns = monotonic_ns() + timeout_ms * 1'000'000;
    for (;;) {
      const int64_t left_ms = (deadline_ns - monotonic_ns()) / 1'000'000;
      if (left_ms <= 0 || !read_some(static_cast<int>(left_ms))) break;
    }
    int status = 0;
    // EOF can come just before the exit: poll the exit up to the deadline.
    while (waitpid(pid_, &status, WNOHANG) == 0) {
      if (monotonic_ns() >= deadline_ns) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
        reaped_ = true;
        return -1;
      }
      usleep(10'000);
    }
    reaped_ = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // Asks the child to stop and returns its exit status (see wait_exit).
  int terminate(int64_t timeout_ms) {
    if (pid_ > 0 && !reaped_) kill(pid_, SIGTERM);
    return wait_exit(timeout_ms);
  }

  const std::string& output() const { return output_; }

 private:
  // One bounded read; false on EOF, error or timeout.
  bool read_some(int timeout_ms) {
    if (out_fd_ < 0) return false;
    pollfd p{out_fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return false;
    char buf[4096];
    const ssize_t n = read(out_fd_, buf, sizeof buf);
    if (n <= 0) return false;
    output_.append(buf, static_cast<size_t>(n));
    return true;
  }

  pid_t pid_ = -1;
  int out_fd_ = -1;
  bool reaped_ = false;
  std::string output_;
};

}  // namespace ceilpose::test
