#pragma once
// SIGTERM, SIGINT and SIGHUP delivered as data on a signalfd instead of to a
// handler, so the control thread handles them in its own loop with no
// async-signal-safety concerns. Construct before any other thread starts:
// threads inherit the blocked mask, so the signals can only arrive here.
//
// Threads: construct and wait() from the control thread.
#include <csignal>

namespace ceilpose::daemon {

// First thing in main(): SIGTERM, SIGINT and SIGHUP blocked for this thread
// (and every thread it starts), and a handler that only notes the signal for
// threads that do not block them yet: libraries' own threads started before
// main (lttng-ust's, through libcamera) unblock nothing of ours but can be
// handed a process-directed signal in their first instants. A noted signal
// is the first SignalChannel::wait() returns. So a SIGTERM during start-up
// stops the daemon cleanly instead of ending it by signal (issue 28 #15).
void hold_stop_signals();

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
