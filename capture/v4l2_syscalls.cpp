#include "capture/v4l2_syscalls.h"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

namespace ceilpose::capture {
namespace {

class RealV4l2Syscalls final : public V4l2Syscalls {
 public:
  int open(const char* path, int flags) override {
    const int fd = ::open(path, flags | O_CLOEXEC);
    return fd < 0 ? -errno : fd;
  }
  int close(int fd) override { return ::close(fd) < 0 ? -errno : 0; }
  int ioctl(int fd, unsigned long request, void* arg) override {
    int r;
    do {
      r = ::ioctl(fd, request, arg);
    } while (r < 0 && errno == EINTR);
    return r < 0 ? -errno : r;
  }
  int mmap(int fd, size_t length, off_t offset, void** out) override {
    void* p = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
    if (p == MAP_FAILED) return -errno;
    *out = p;
    return 0;
  }
  int munmap(void* addr, size_t length) override { return ::munmap(addr, length) < 0 ? -errno : 0; }
  int poll(pollfd* fd, int timeout_ms) override {
    const int r = ::poll(fd, 1, timeout_ms);
    return r < 0 ? -errno : r;
  }
};

}  // namespace

V4l2Syscalls& real_v4l2_syscalls() {
  static RealV4l2Syscalls sys;
  return sys;
}

}  // namespace ceilpose::capture
