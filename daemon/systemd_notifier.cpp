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

void SystemdNotifier::send(const std::string& message, int wait_ms) {
  if (fd_ < 0) return;
  for (;;) {
    if (::send(fd_, message.data(), message.size(), MSG_NOSIGNAL) >= 0) return;
    if (errno == EINTR) continue;
    if (errno == EAGAIN && wait_ms > 0) {
      // A connected datagram socket polls writable once the peer's queue has room.
      pollfd p{fd_, POLLOUT, 0};
      const int ready = poll(&p, 1, wait_ms);
      wait_ms = 0;
      if (ready > 0) continue;
    }
    break;
  }
  const int error = errno;
  // The first loss, then every 100th: a stuck reader must not flood the log.
  if (dropped_++ % 100 == 0) {
    const std::string first_line = message.substr(0, message.find('\n'));
    spdlog::warn("systemd notify socket: {} not sent ({}); {} message(s) lost so far", first_line,
                 error == EAGAIN ? "its reader has stopped reading" : std::strerror(error),
                 dropped_);
  }
}

void SystemdNotifier::ready(const std::string& status) {
  send("READY=1\nSTATUS=" + status, kStateWaitMs);
}
void SystemdNotifier::status(const std::string& status) { send("STATUS=" + status, 0); }
void SystemdNotifier::watchdog() { send("WATCHDOG=1", 0); }
void SystemdNotifier::reloading() {
  send("RELOADING=1\nSTATUS=reloading configuration", kStateWaitMs);
}
void SystemdNotifier::reloaded() { send("READY=1", kStateWaitMs); }
void SystemdNotifier::stopping() { send("STOPPING=1\nSTATUS=stopping", kStateWaitMs); }

}  // namespace ceilpose::daemon
