#pragma once
// Test support: ceilposed as a child process, with a NOTIFY_SOCKET the test
// owns (an AF_UNIX datagram socket, as systemd's), stdout and stderr captured,
// and bounded waits everywhere.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tests/support/child_process.h"

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

// ceilposed as a child process, stdout and stderr captured. The systemd
// protocol variables of whoever runs ctest are not passed on unless `env`
// sets them.
class DaemonProcess : public ChildProcess {
 public:
  // Starts ceilposed with `args`; `env` adds to (or, with an empty value,
  // removes from) the test's environment. Throws when it cannot start.
  // `stdout_fd` >= 0: the daemon's stdout (not captured), see ChildOptions.
  DaemonProcess(const std::vector<std::string>& args, const std::map<std::string, std::string>& env,
                int stdout_fd = -1);
  // What the daemon logged so far: the tests' failure messages.
  const std::string& err() { return error_output(); }
};

// Runs ceilposed to completion (bounded) and returns exit + outputs.
struct RunResult {
  ExitStatus exit;
  std::string out;
  std::string err;
};
RunResult run_daemon(const std::vector<std::string>& args, int timeout_ms = 20000,
                     const std::map<std::string, std::string>& env = {});

// A name unique to this test process and call, e.g. "/ceilpose-test-1234-3".
std::string unique_shm_name();
bool shm_exists(const std::string& name);
// Unlinks what a daemon leaves under `shm` (its pose, wake and fleet
// segments stay after a clean stop, docs/ipc.md): every test's clean-up.
void remove_daemon_segments(const std::string& shm);
// Writes `text` to a fresh file under the test temp dir and returns its path.
std::string write_temp_file(const std::string& stem, const std::string& text);

}  // namespace ceilpose::test
