#pragma once
// The system calls the V4L2 backend makes, behind a small interface so that
// tests can put a fake driver at exactly this boundary (tests/capture/). Every
// call returns its result, or -errno on failure, and never logs: the caller
// knows the device and the buffer and logs with that context.
#include <poll.h>
#include <sys/types.h>

#include <cstddef>

#include "core/unique_fd.h"

namespace ceilpose::capture {

class V4l2Syscalls : public FdCloser {
 public:
  virtual ~V4l2Syscalls() = default;
  // open(2) of a device node; >= 0 is the fd.
  virtual int open(const char* path, int flags) = 0;
  int close(int fd) override = 0;
  // ioctl(2), retried on EINTR; 0 (or the ioctl's non-negative result) or -errno.
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  // mmap(2) of a buffer, PROT_READ|PROT_WRITE, MAP_SHARED. 0 and *out, or -errno.
  virtual int mmap(int fd, size_t length, off_t offset, void** out) = 0;
  virtual int munmap(void* addr, size_t length) = 0;
  // poll(2) for one fd; the number of ready fds (0 on timeout) or -errno.
  virtual int poll(pollfd* fd, int timeout_ms) = 0;
};

// The real syscalls; stateless, shared by all sources.
V4l2Syscalls& real_v4l2_syscalls();

}  // namespace ceilpose::capture
