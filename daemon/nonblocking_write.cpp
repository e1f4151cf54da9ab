#include "daemon/nonblocking_write.h"

#include <poll.h>
#include <unistd.h>

#include <cerrno>

namespace ceilpose::daemon {

WriteOutcome write_without_blocking(int fd, const char* data, size_t size) {
  size_t done = 0;
  while (done < size) {
    pollfd p{fd, POLLOUT, 0};
    const int ready = poll(&p, 1, 0);
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return WriteOutcome::kFailed;
    if ((p.revents & (POLLERR | POLLHUP)) != 0) {
      errno = EPIPE;
      return WriteOutcome::kClosed;
    }
    if (ready == 0 || (p.revents & POLLOUT) == 0) return WriteOutcome::kDropped;
    const ssize_t n = write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return WriteOutcome::kDropped;
    if (n < 0 && errno == EPIPE) return WriteOutcome::kClosed;
    if (n < 0) return WriteOutcome::kFailed;
    done += static_cast<size_t>(n);
  }
  return WriteOutcome::kWritten;
}

}  // namespace ceilpose::daemon
