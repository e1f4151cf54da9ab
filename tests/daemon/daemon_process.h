#pragma once
// Test support: ceilposed as a child process, with a NOTIFY_SOCKET the test
// owns (an AF_UNIX datagram socket, as systemd's), stdout and stderr captured
// to files, and bounded waits everywhere.
#include <sys/types.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace ceilpose::test {

// The test's end of the sd_notify protocol.
class NotifySocket {
 public:
  NotifySocket();  // binds a fresh path under the test temp dir
  ~NotifySocket();
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  const std::string& path() const { return path_; }
  // Next datagram within timeout_ms, or nullopt.
  std::optional<std::string> receive(int timeout_ms);
  // Waits for a datagram containing `line` (e.g. "READY=1"); false on timeout.
  bool wait_for(const std::string& line, int timeout_ms);

 private:
  int fd_ = -1;
  std::string path_;
};

struct Exit {
  bool exited = false;  // false: killed by a signal (or still running at timeout)
  int code = -1;        // exit status when exited
  int signal = 0;
};

class DaemonProcess {
 public:
  // Starts ceilposed with `args`; `env` adds to (or, with an empty value,
  // removes from) the test's environment.
  DaemonProcess(const std::vector<std::string>& args,
                const std::map<std::string, std::string>& env);
  ~DaemonProcess();  // SIGKILLs a child that is still running
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  pid_t pid() const { return pid_; }
  void signal(int sig);
  bool running();
  // Waits up to timeout_ms for the child to end; `exited`/`signal` unset on timeout.
  std::optional<Exit> wait(int timeout_ms);
  std::string out() const;  // captured stdout so far
  std::string err() const;  // captured stderr so far

 private:
  pid_t pid_ = -1;
  std::optional<Exit> exit_;
  std::string out_path_;
  std::string err_path_;
};

// Runs ceilposed to completion (bounded) and returns exit + outputs.
struct RunResult {
  Exit exit;
  std::string out;
  std::string err;
};
RunResult run_daemon(const std::vector<std::string>& args, int timeout_ms = 20000,
                     const std::map<std::string, std::string>& env = {});

// A name unique to this test process and call, e.g. "/ceilpose-test-1234-3".
std::string unique_shm_name();
bool shm_exists(const std::string& name);
// Writes `text` to a fresh file under the test temp dir and returns its path.
std::string write_temp_file(const std::string& stem, const std::string& text);

}  // namespace ceilpose::test
