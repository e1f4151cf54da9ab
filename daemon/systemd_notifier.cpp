#include "daemon/systemd_notifier.h"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <cstdlib>
#include <cstring>

namespace ceilpose::daemon {

SystemdNotifier::SystemdNotifier() {
  active_ = std::getenv("NOTIFY_SOCKET") != nullptr;
  uint64_t usec = 0;
  // > 0 only when WATCHDOG_USEC is set and WATCHDOG_PID, if set, is us.
  const int r = sd_watchdog_enabled(0, &usec);
  if (r > 0) {
    watchdog_usec_ = usec;
  } else if (r < 0) {
    spdlog::warn("systemd watchdog: cannot parse WATCHDOG_USEC/WATCHDOG_PID: {}",
                 std::strerror(-r));
  }
}

void SystemdNotifier::send(const std::string& message) {
  if (!active_) return;
  const int r = sd_notify(0, message.c_str());
  if (r < 0) spdlog::warn("sd_notify(\"{}\") failed: {}", message, std::strerror(-r));
}

void SystemdNotifier::ready(const std::string& status) { send("READY=1\nSTATUS=" + status); }
void SystemdNotifier::status(const std::string& status) { send("STATUS=" + status); }
void SystemdNotifier::watchdog() { send("WATCHDOG=1"); }
void SystemdNotifier::reloading() { send("RELOADING=1\nSTATUS=reloading configuration"); }
void SystemdNotifier::reloaded() { send("READY=1"); }
void SystemdNotifier::stopping() { send("STOPPING=1\nSTATUS=stopping"); }

}  // namespace ceilpose::daemon
