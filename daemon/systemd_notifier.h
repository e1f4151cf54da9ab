#pragma once
// The daemon's side of the systemd notify protocol (sd_notify(3)): READY=1
// once the service works, STATUS= for `systemctl status`, WATCHDOG=1 while it
// makes progress, RELOADING=1/STOPPING=1 around reload and stop. Without
// NOTIFY_SOCKET (a terminal) every call is a no-op.
//
// Threads: the control (main) thread only, which is also what NotifyAccess=main
// requires of the messages' sender.
#include <cstdint>
#include <string>

namespace ceilpose::daemon {

class SystemdNotifier {
 public:
  SystemdNotifier();

  bool active() const { return active_; }
  // WatchdogSec of the unit in microseconds, 0 when the watchdog is off.
  uint64_t watchdog_usec() const { return watchdog_usec_; }

  void ready(const std::string& status);
  void status(const std::string& status);
  void watchdog();
  void reloading();
  void reloaded();
  void stopping();

 private:
  void send(const std::string& message);
  bool active_ = false;
  uint64_t watchdog_usec_ = 0;
};

}  // namespace ceilpose::daemon
