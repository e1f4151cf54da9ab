#include "daemon/systemd_notifier.h"

#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "core/clock.h"

namespace ceilpose::daemon {
namespace {

// A connected, non-blocking datagram socket to NOTIFY_SOCKET ("/path" or
// "@abstract"), or -1 with the reason logged.
int connect_notify_socket(const char* path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const size_t length = std::strlen(path);
  if ((path[0] != '/' && path[0] != '@') || length < 2 || length >= sizeof addr.sun_path) {
    spdlog::warn("NOTIFY_SOCKET={}: not an absolute or abstract socket path; not notifying systemd",
                 path);
    return -1;
  }
  std::memcpy(addr.sun_path, path, length);
  if (path[0] == '@') addr.sun_path[0] = '\0';
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd < 0) {
    spdlog::warn("NOTIFY_SOCKET={}: socket: {}; not notifying systemd", path, std::strerror(errno));
    return -1;
  }
  const auto addr_size = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + length);
  if (connect(fd, reinterpret_cast<const sockaddr*>(&addr), addr_size) != 0) {
    spdlog::warn("NOTIFY_SOCKET={}: connect: {}; not notifying systemd", path,
                 std::strerror(errno));
    close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

SystemdNotifier::SystemdNotifier() {
  if (const char* path = std::getenv("NOTIFY_SOCKET"); path != nullptr && path[0] != '\0')
    fd_ = connect_notify_socket(path);
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

SystemdNotifier::~SystemdNotifier() {
  if (fd_ >= 0) close(fd_);
}

bool SystemdNotifier::send_now(const std::string& message, int wait_ms) {
  for (;;) {
    if (::send(fd_, message.data(), message.size(), MSG_NOSIGNAL) >= 0) return true;
    if (errno == EINTR) continue;
    if (errno == EAGAIN && wait_ms > 0) {
      // A connected datagram socket polls writable once the peer's queue has room.
      pollfd p{fd_, POLLOUT, 0};
      const int ready = poll(&p, 1, wait_ms);
      wait_ms = 0;
      if (ready > 0) continue;
      errno = EAGAIN;
    }
    return false;
  }
}

void SystemdNotifier::count_lost(const std::string& message, int error) {
  // The first loss, then every 100th: a stuck reader must not flood the log.
  if (dropped_++ % 100 == 0) {
    const std::string first_line = message.substr(0, message.find('\n'));
    spdlog::warn("systemd notify socket: {} not sent ({}); {} message(s) lost so far", first_line,
                 error == EAGAIN ? "its reader has stopped reading" : std::strerror(error),
                 dropped_);
  }
}

void SystemdNotifier::flush() {
  if (queued_.empty()) return;
  while (!queued_.empty()) {
    if (!send_now(queued_.front(), 0)) {
      if (errno == EAGAIN) return;  // still full: the next flush() tries again
      count_lost(queued_.front(), errno);
    }
    queued_.pop_front();
  }
  spdlog::info("systemd notify socket: its reader read again after {} ms; queued messages sent",
               (monotonic_ns() - queued_since_ns_) / kMsNs);
}

void SystemdNotifier::send_state(const std::string& message) {
  if (fd_ < 0) return;
  const bool was_waiting = !queued_.empty();
  if (!was_waiting) {
    if (send_now(message, kStateWaitMs)) return;
    if (errno != EAGAIN) return count_lost(message, errno);
    queued_since_ns_ = monotonic_ns();
  }
  if (queued_.size() == kMaxQueuedStates) {
    count_lost(queued_.front(), EAGAIN);
    queued_.pop_front();
  }
  queued_.push_back(message);
  if (!was_waiting) {
    spdlog::warn(
        "systemd notify socket: {} waits: its reader has read nothing for {} ms; sent as soon "
        "as it reads again",
        message.substr(0, message.find('\n')), kStateWaitMs);
  } else {
    flush();
  }
}

void SystemdNotifier::send_periodic(const std::string& message) {
  if (fd_ < 0) return;
  if (!queued_.empty()) {
    flush();
    // Behind the state messages, never before them.
    if (!queued_.empty()) return count_lost(message, EAGAIN);
  }
  if (!send_now(message, 0)) count_lost(message, errno);
}

void SystemdNotifier::ready(const std::string& status) { send_state("READY=1\nSTATUS=" + status); }
void SystemdNotifier::status(const std::string& status) { send_periodic("STATUS=" + status); }
void SystemdNotifier::watchdog() { send_periodic("WATCHDOG=1"); }
void SystemdNotifier::reloading() { send_state("RELOADING=1\nSTATUS=reloading configuration"); }
void SystemdNotifier::reloaded() { send_state("READY=1"); }
void SystemdNotifier::stopping() { send_state("STOPPING=1\nSTATUS=stopping"); }

}  // namespace ceilpose::daemon
