#pragma once
// The daemon's side of the systemd notify protocol (sd_notify(3)): READY=1
// once the service works, STATUS= for `systemctl status`, WATCHDOG=1 while it
// makes progress, RELOADING=1/STOPPING=1 around reload and stop. Without
// NOTIFY_SOCKET (a terminal) every call is a no-op.
//
// Never blocks for long: libsystemd's sd_notify() sends on a blocking socket,
// and a notify socket whose reader has stopped reading (a hung or busy PID 1,
// a supervisor that only reads READY=1) fills after net.unix.max_dgram_qlen
// datagrams (10 by default) and then held the control thread in sendmsg(2):
// SIGTERM went unanswered for good. Here a message that changes the unit's
// state (READY, RELOADING, STOPPING) waits at most kStateWaitMs for room and,
// if there is still none, stays queued and is sent by flush() as soon as the
// reader reads again: systemd must not be left believing a reload never
// ended (a CI run lost READY=1 after SIGHUP while its reader was slow).
// Periodic messages (STATUS, WATCHDOG) never wait, go only after every
// queued state message, and are otherwise dropped and counted.
//
// Threads: the control (main) thread only, which is also what NotifyAccess=main
// requires of the messages' sender.
#include <cstdint>
#include <deque>
#include <string>

namespace ceilpose::daemon {

class SystemdNotifier {
 public:
  static constexpr int kStateWaitMs = 200;
  // State messages kept for a reader that stopped: a SIGHUP storm must not
  // grow the queue without bound (the oldest go first, counted as dropped).
  static constexpr size_t kMaxQueuedStates = 16;

  SystemdNotifier();
  ~SystemdNotifier();
  SystemdNotifier(const SystemdNotifier&) = delete;
  SystemdNotifier& operator=(const SystemdNotifier&) = delete;

  bool active() const { return fd_ >= 0; }
  // WatchdogSec of the unit in microseconds, 0 when the watchdog is off.
  uint64_t watchdog_usec() const { return watchdog_usec_; }
  // Messages lost because the notify socket stayed full.
  uint64_t dropped() const { return dropped_; }
  // State messages still waiting for room: call flush() soon.
  bool has_queued() const { return !queued_.empty(); }
  // Sends queued state messages, in order, while the socket has room.
  void flush();

  void ready(const std::string& status);
  void status(const std::string& status);
  void watchdog();
  void reloading();
  void reloaded();
  void stopping();

 private:
  // One datagram; false (errno set) if it was not sent within wait_ms.
  bool send_now(const std::string& message, int wait_ms);
  void send_state(const std::string& message);
  void send_periodic(const std::string& message);
  void count_lost(const std::string& message, int error);
  int fd_ = -1;
  std::deque<std::string> queued_;
  int64_t queued_since_ns_ = 0;
  uint64_t watchdog_usec_ = 0;
  uint64_t dropped_ = 0;
};

}  // namespace ceilpose::daemon
