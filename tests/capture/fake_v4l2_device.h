#pragma once
// A fake V4L2 capture driver at the syscall boundary of V4l2Source. It keeps
// the driver's side of the mmap streaming protocol (formats, buffer queue,
// STREAMON/OFF, controls) and produces a frame into the oldest queued buffer
// whenever poll() is called, so a test drives time by calling next(). Faults
// are scripted by frame number: a dequeue error (EIO, ENODEV: the device then
// vanishes for some reopen attempts), a spurious EAGAIN, or a stall.
//
// Thread: one thread at a time (the source's); the mutex only makes the
// counters safe to read from the test thread while a CaptureThread runs.
#include <linux/videodev2.h>

#include <cstdint>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "capture/v4l2_syscalls.h"

namespace ceilpose::capture::testing {

class FakeV4l2Device : public V4l2Syscalls {
 public:
  struct Control {
    int32_t minimum = 0;
    int32_t maximum = 10000;
    int32_t value = 0;
  };

  explicit FakeV4l2Device(std::string path = "/dev/video0");
  ~FakeV4l2Device() override;

  // ---- driver configuration (before open) ----
  // Formats S_FMT accepts as asked; any other is answered with the first of
  // these (what most drivers do), unless listed in refuse_with_einval.
  std::vector<uint32_t> formats{V4L2_PIX_FMT_YUYV};
  std::set<uint32_t> refuse_with_einval;
  uint32_t max_width = 1920;
  uint32_t max_height = 1080;
  bool timeperframe = true;
  bool monotonic_timestamps = true;
  // What the stamps mark: V4L2_BUF_FLAG_TSTAMP_SRC_EOF (end of frame, most
  // drivers) or V4L2_BUF_FLAG_TSTAMP_SRC_SOE (start of exposure).
  uint32_t timestamp_source = V4L2_BUF_FLAG_TSTAMP_SRC_EOF;
  std::map<uint32_t, Control> controls;  // present controls; absent ids answer EINVAL
  // Frame numbers (0-based, in production order) after which the driver skips
  // one sequence number, as a driver that lost a frame does.
  std::set<uint64_t> sequence_gap_after;
  // What an MJPEG frame carries (a real JPEG file's bytes, or garbage).
  std::vector<uint8_t> mjpeg_payload;

  // ---- scripted faults ----
  // The DQBUF that would return frame `frame` fails with -error instead. For
  // ENODEV the device also vanishes: the next `reopen_failures` open() calls
  // fail with ENOENT.
  void fail_dequeue_at(uint64_t frame, int error, int reopen_failures = 0);
  // One DQBUF at frame `frame` returns EAGAIN although poll said readable.
  void spurious_eagain_at(uint64_t frame);
  // From frame `frame` on, no frame is produced (poll times out) until the
  // device is closed and reopened.
  void stall_at(uint64_t frame);

  // ---- observations ----
  uint64_t frames_produced() const;
  int opens() const;
  int open_fds() const;
  int mapped_buffers() const;
  int queued_buffers() const;
  bool streaming() const;
  uint32_t current_format() const;
  int32_t control_value(uint32_t id) const;
  // Indices in the order DQBUF handed them out / QBUF got them back.
  std::vector<uint32_t> dequeue_order() const;
  std::vector<uint32_t> queue_order() const;
  // The stamp of every frame produced, as the driver wrote it (µs resolution).
  std::vector<int64_t> stamps_written() const;
  // Reads the frame number the fake wrote into a buffer's first 8 bytes.
  static uint64_t stamp_of(const uint8_t* data);

  // ---- V4l2Syscalls ----
  int open(const char* path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  int mmap(int fd, size_t length, off_t offset, void** out) override;
  int munmap(void* addr, size_t length) override;
  int poll(pollfd* fd, int timeout_ms) override;

 private:
  struct Buffer {
    std::vector<uint8_t> memory;
    bool queued = false;
    bool done = false;
    int mapped = 0;
    v4l2_buffer info{};
  };
  enum class Fault { kNone, kError, kEagain };

  int ioctl_locked(unsigned long request, void* arg);
  bool produce_locked();
  Buffer* buffer_at(void* addr);

  mutable std::mutex mutex_;
  const std::string path_;
  int next_fd_ = 100;
  int fd_ = -1;        // the open fd
  bool gone_ = false;  // vanished (ENODEV): the old fd answers ENODEV until reopened
  int opens_ = 0;
  int fail_opens_ = 0;
  uint32_t fourcc_ = V4L2_PIX_FMT_YUYV;
  uint32_t width_ = 640;
  uint32_t height_ = 480;
  v4l2_fract timeperframe_{1, 30};
  bool streaming_ = false;
  std::vector<Buffer> buffers_;
  std::vector<Buffer> orphans_;       // freed by REQBUFS(0) or close while still mapped
  std::vector<uint32_t> incoming_;    // queued, not yet filled, oldest first
  std::vector<uint32_t> done_order_;  // indices of filled buffers, oldest first
  uint64_t produced_ = 0;
  uint32_t sequence_ = 0;
  bool stalled_ = false;
  std::map<uint64_t, std::pair<Fault, int>> dequeue_faults_;
  std::map<uint64_t, int> reopen_failures_;
  std::set<uint64_t> stall_at_;
  std::vector<uint32_t> dequeue_order_;
  std::vector<uint32_t> queue_order_;
  std::vector<int64_t> stamps_;
};

}  // namespace ceilpose::capture::testing
