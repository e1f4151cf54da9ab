#pragma once
// The one owner of a file descriptor: closes it once, on destruction or
// reset(), through ::close or through a closer that the fd came from (the
// V4L2 syscall layer, which tests replace with a fake device). Move-only.
#include <unistd.h>

#include <utility>

namespace ceilpose {

// Something that can close the fds it hands out.
class FdCloser {
 public:
  virtual ~FdCloser() = default;
  virtual int close(int fd) = 0;
};

class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd, FdCloser* closer = nullptr) : fd_(fd), closer_(closer) {}
  ~UniqueFd() { reset(); }
  UniqueFd(UniqueFd&& o) noexcept : fd_(std::exchange(o.fd_, -1)), closer_(o.closer_) {}
  UniqueFd& operator=(UniqueFd&& o) noexcept {
    if (this != &o) {
      reset();
      fd_ = std::exchange(o.fd_, -1);
      closer_ = o.closer_;
    }
    return *this;
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  // Gives the fd up without closing it.
  int release() { return std::exchange(fd_, -1); }
  void reset() {
    if (fd_ >= 0) {
      if (closer_ != nullptr) {
        closer_->close(fd_);
      } else {
        ::close(fd_);
      }
    }
    fd_ = -1;
  }

 private:
  int fd_ = -1;
  FdCloser* closer_ = nullptr;
};

}  // namespace ceilpose
