#pragma once
// SIGTERM, SIGINT and SIGHUP delivered as data on a signalfd instead of to a
// handler, so the control thread handles them in its own loop with no
// async-signal-safety concerns. Construct before any other thread starts:
// threads inherit the blocked mask, so the signals can only arrive here.
//
// Threads: construct and wait() from the control thread.
#include <csignal>

namespace ceilpose::daemon {

class SignalChannel {
 public:
  SignalChannel();  // throws std::system_error if the signalfd cannot be made
  ~SignalChannel();
  SignalChannel(const SignalChannel&) = delete;
  SignalChannel& operator=(const SignalChannel&) = delete;

  // Waits up to timeout_ms for a signal; returns its number, or 0 on timeout.
  int wait(int timeout_ms);

 private:
  int fd_ = -1;
  sigset_t previous_{};
};

}  // namespace ceilpose::daemon
