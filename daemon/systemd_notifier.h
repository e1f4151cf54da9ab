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
// SIGTERM went unanswered for good. Here a message waits at most
// kStateWaitMs for room when it changes the unit's state (READY, RELOADING,
// STOPPING), not at all when it is periodic (STATUS, WATCHDOG), and is
// otherwise dropped and counted.
//
// Threads: the control (main) thread only, which is also what NotifyAccess=main
// requires of the messages' sender.
#include <cstdint>
#include <string>

namespace ceilpose::daemon {

class SystemdNotifier {
 public:
  static constexpr int kStateWaitMs = 200;

  SystemdNotifier();
  ~SystemdNotifier();
  SystemdNotifier(const SystemdNotifier&) = delete;
  SystemdNotifier& operator=(const SystemdNotifier&) = delete;

  bool active() const { return fd_ >= 0; }
  // WatchdogSec of the unit in microseconds, 0 when the watchdog is off.
  uint64_t watchdog_usec() const { return watchdog_usec_; }
  // Messages lost because the notify socket stayed full.
  uint64_t dropped() const { return dropped_; }

  void ready(const std::string& status);
  void status(const std::string& status);
  void watchdog();
  void reloading();
  void reloaded();
  void stopping();

 private:
  void send(const std::string& message, int wait_ms);
  int fd_ = -1;
  uint64_t watchdog_usec_ = 0;
  uint64_t dropped_ = 0;
};

}  // namespace ceilpose::daemon
