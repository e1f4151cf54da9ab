#pragma once
// Test support: a program run as a child process, for tests and benchmarks
// that drive ceilposed, ceilposectl or a DDS peer from outside. Its stdout
// (and, on request, stderr) come back through pipes read without blocking
// and kept up to a bound; every wait has a timeout; the child is always
// reaped, so a failing test leaves neither a zombie nor a hang behind.
#include <sys/types.h>

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace ceilpose::test {

// How a child ended.
struct ExitStatus {
  bool exited = false;  // false: ended by a signal
  int code = -1;        // exit status when exited, else -1
  int signal = 0;       // the signal that ended it, else 0
};

struct ChildOptions {
  // Added to this process's environment; an empty value removes the name.
  std::map<std::string, std::string> env;
  // False: the child writes to this process's stderr, so its diagnostics
  // stand in the test log as they happen.
  bool capture_stderr = false;
  // Kept per stream; output past it is still read (the child never blocks
  // on a full pipe) and dropped.
  size_t max_output_bytes = size_t{16} << 20;
  // >= 0: the child's stdout is this descriptor (a pipe the test never
  // reads, a closed pipe, /dev/full) instead of a captured pipe.
  int stdout_fd = -1;
};

class ChildProcess {
 public:
  // argv[0] is the program's path (no PATH search); stdin is /dev/null.
  explicit ChildProcess(const std::vector<std::string>& argv, ChildOptions options = {});
  ~ChildProcess();  // SIGKILLs a child still running, then reaps it
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool started() const { return pid_ > 0; }
  // Why the program could not start ("cannot start <path>: <reason>").
  const std::string& start_error() const { return start_error_; }
  pid_t pid() const { return pid_; }

  // Sends `sig` unless the child has been reaped (its pid may be reused).
  void signal(int sig);
  bool running();
  // Waits up to timeout_ms for the exit, reading output meanwhile; nullopt
  // when the child still runs (it is left running).
  std::optional<ExitStatus> wait(int timeout_ms);
  // Waits up to timeout_ms, then SIGKILLs. Returns the exit status, or -1
  // when the child had to be killed, died of a signal or never started.
  int wait_exit(int timeout_ms);
  // SIGTERM, then SIGKILL if it has not ended within grace_ms.
  ExitStatus terminate(int grace_ms);
  // SIGKILL now and reap.
  ExitStatus kill();

  // Reads stdout until `needle` appears, EOF or timeout; returns all of it so far.
  const std::string& read_until(const std::string& needle, int timeout_ms);
  // The same for stderr; returns at once with "" unless capture_stderr.
  const std::string& read_error_until(const std::string& needle, int timeout_ms);
  // What the child wrote so far, read without blocking.
  const std::string& output();
  const std::string& error_output();  // empty unless capture_stderr

 private:
  struct Stream {
    int fd = -1;
    std::string text;
  };
  // Reads what the pipes hold, first waiting up to timeout_ms for data or
  // for the exit.
  void pump(int timeout_ms);
  const std::string& read_until(Stream& s, const std::string& needle, int timeout_ms);
  void read_available(Stream& s);
  // Reaps the child if it has ended; true once reaped.
  bool reap(bool block);

  pid_t pid_ = -1;
  int pidfd_ = -1;  // readable once the child ends; -1 where pidfd_open is missing
  Stream out_;
  Stream err_;
  size_t max_output_bytes_;
  std::optional<ExitStatus> exit_;
  std::string start_error_;
};

// What a program run to its end wrote, and how it ended.
struct RunOutput {
  int exit_code = -1;  // -1: killed at the deadline, ended by a signal or never started
  std::string out;
  std::string err;
  // Why it could not start or had to be killed ("cannot start ...", "...
  // still running after N ms, killed"); empty otherwise.
  std::string failure;
};

// Runs `argv` with stdout and stderr captured apart until it ends; kills it
// after timeout_ms.
RunOutput run_to_end(const std::vector<std::string>& argv, int timeout_ms, int stdout_fd = -1);

}  // namespace ceilpose::test
