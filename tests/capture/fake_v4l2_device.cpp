#include "fake_v4l2_device.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "core/clock.h"

namespace ceilpose::capture::testing {
namespace {

constexpr uint32_t kPage_bytes = 4096;

uint32_t bytes_per_pixel_of(uint32_t fourcc) {
  switch (fourcc) {
    case V4L2_PIX_FMT_YUYV:
      return 2;
    case V4L2_PIX_FMT_RGB24:
    case V4L2_PIX_FMT_BGR24:
      return 3;
    case V4L2_PIX_FMT_GREY:
      return 1;
    default:
      return 0;  // compressed
  }
}

}  // namespace

FakeV4l2Device::FakeV4l2Device(std::string path) : path_(std::move(path)) {}
FakeV4l2Device::~FakeV4l2Device() = default;

void FakeV4l2Device::fail_dequeue_at(uint64_t frame, int error, int reopen_failures) {
  std::lock_guard<std::mutex> lock(mutex_);
  dequeue_faults_[frame] = {Fault::kError, error};
  reopen_failures_[frame] = reopen_failures;
}
void FakeV4l2Device::spurious_eagain_at(uint64_t frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  dequeue_faults_[frame] = {Fault::kEagain, EAGAIN};
}
void FakeV4l2Device::stall_at(uint64_t frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  stall_at_.insert(frame);
}

uint64_t FakeV4l2Device::frames_produced() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return produced_;
}
int FakeV4l2Device::opens() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return opens_;
}
int FakeV4l2Device::open_fds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fd_ >= 0 ? 1 : 0;
}
int FakeV4l2Device::mapped_buffers() const {
  std::lock_guard<std::mutex> lock(mutex_);
  int n = 0;
  for (const auto& b : buffers_) n += b.mapped;
  for (const auto& b : orphans_) n += b.mapped;
  return n;
}
int FakeV4l2Device::queued_buffers() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(incoming_.size());
}
bool FakeV4l2Device::streaming() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return streaming_;
}
uint32_t FakeV4l2Device::current_format() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fourcc_;
}
int32_t FakeV4l2Device::control_value(uint32_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = controls.find(id);
  return it == controls.end() ? -1 : it->second.value;
}
std::vector<uint32_t> FakeV4l2Device::dequeue_order() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dequeue_order_;
}
std::vector<uint32_t> FakeV4l2Device::queue_order() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_order_;
}

std::vector<int64_t> FakeV4l2Device::stamps_written() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stamps_;
}
uint64_t FakeV4l2Device::stamp_of(const uint8_t* data) {
  uint64_t v;
  std::memcpy(&v, data, sizeof v);
  return v;
}

int FakeV4l2Device::open(const char* path, int /*flags*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (path_ != path) return -ENOENT;
  if (fail_opens_ > 0) {
    --fail_opens_;
    return -ENOENT;  // the node is gone until the device re-enumerates
  }
  if (fd_ >= 0) return -EBUSY;
  fd_ = next_fd_++;
  gone_ = false;
  stalled_ = false;
  ++opens_;
  return fd_;
}

int FakeV4l2Device::close(int fd) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (fd != fd_) return -EBADF;
  streaming_ = false;
  for (auto& b : buffers_) {
    if (b.mapped > 0) orphans_.push_back(std::move(b));
  }
  buffers_.clear();
  incoming_.clear();
  done_order_.clear();
  fd_ = -1;
  return 0;
}

FakeV4l2Device::Buffer* FakeV4l2Device::buffer_at(void* addr) {
  for (auto& b : buffers_) {
    if (b.memory.data() == addr) return &b;
  }
  for (auto& b : orphans_) {
    if (b.memory.data() == addr) return &b;
  }
  return nullptr;
}

int FakeV4l2Device::mmap(int fd, size_t length, off_t offset, void** out) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (fd != fd_) return -EBADF;
  if (gone_) return -ENODEV;
  const size_t index = static_cast<size_t>(offset) / kPage_bytes;
  if (index >= buffers_.size() || length > buffers_[index].memory.size()) return -EINVAL;
  ++buffers_[index].mapped;
  *out = buffers_[index].memory.data();
  return 0;
}

int FakeV4l2Device::munmap(void* addr, size_t /*length*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  Buffer* b = buffer_at(addr);
  if (b == nullptr || b->mapped == 0) return -EINVAL;
  --b->mapped;
  for (auto it = orphans_.begin(); it != orphans_.end(); ++it) {
    if (it->memory.data() == addr && it->mapped == 0) {
      orphans_.erase(it);
      break;
    }
  }
  return 0;
}

// Fills the oldest queued buffer, as the hardware would at the next frame.
bool FakeV4l2Device::produce_locked() {
  if (incoming_.empty()) return false;
  const uint32_t index = incoming_.front();
  incoming_.erase(incoming_.begin());
  Buffer& b = buffers_[index];
  const uint64_t frame = produced_++;
  if (fourcc_ == V4L2_PIX_FMT_MJPEG) {
    std::memcpy(b.memory.data(), mjpeg_payload.data(),
                std::min(mjpeg_payload.size(), b.memory.size()));
    b.info.bytesused = static_cast<uint32_t>(std::min(mjpeg_payload.size(), b.memory.size()));
  } else {
    std::memcpy(b.memory.data(), &frame, sizeof frame);
    b.info.bytesused = static_cast<uint32_t>(b.memory.size());
  }
  const int64_t now_ns = monotonic_ns();
  b.info.timestamp.tv_sec = static_cast<time_t>(now_ns / 1'000'000'000);
  b.info.timestamp.tv_usec = static_cast<suseconds_t>((now_ns % 1'000'000'000) / 1000);
  b.info.flags =
      (monotonic_timestamps ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN) |
      timestamp_source;
  stamps_.push_back(static_cast<int64_t>(b.info.timestamp.tv_sec) * 1'000'000'000 +
                    static_cast<int64_t>(b.info.timestamp.tv_usec) * 1000);
  b.info.sequence = sequence_++;
  if (sequence_gap_after.count(frame)) ++sequence_;
  b.info.reserved = static_cast<uint32_t>(frame);  // the frame number, for fault lookup
  b.queued = false;
  b.done = true;
  done_order_.push_back(index);
  return true;
}

int FakeV4l2Device::poll(pollfd* p, int timeout_ms) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    p->revents = 0;
    if (p->fd != fd_ || gone_) {
      p->revents = POLLERR;
      return 1;
    }
    if (!done_order_.empty()) {
      p->revents = POLLIN;
      return 1;
    }
    if (streaming_ && !stalled_ && stall_at_.count(produced_)) {
      stall_at_.erase(produced_);
      stalled_ = true;
    }
    if (streaming_ && !stalled_) {
      if (produce_locked()) {
        p->revents = POLLIN;
        return 1;
      }
      p->revents = POLLERR;  // streaming with no buffer queued: videobuf2 says POLLERR
      return 1;
    }
  }
  // Stalled or not streaming: nothing arrives within the timeout.
  std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
  return 0;
}

int FakeV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (fd != fd_) return -EBADF;
  if (gone_) return -ENODEV;
  return ioctl_locked(request, arg);
}

int FakeV4l2Device::ioctl_locked(unsigned long request, void* arg) {
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* cap = static_cast<v4l2_capability*>(arg);
      *cap = v4l2_capability{};
      std::strcpy(reinterpret_cast<char*>(cap->driver), "fake");
      std::strcpy(reinterpret_cast<char*>(cap->card), "Fake ceiling camera");
      cap->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
      cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_S_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return -EINVAL;
      if (streaming_ || !buffers_.empty()) return -EBUSY;
      if (refuse_with_einval.count(f->fmt.pix.pixelformat)) return -EINVAL;
      bool known = false;
      for (uint32_t x : formats) known |= x == f->fmt.pix.pixelformat;
      fourcc_ = known ? f->fmt.pix.pixelformat : formats.front();
      width_ = std::min(f->fmt.pix.width, max_width);
      height_ = std::min(f->fmt.pix.height, max_height);
      [[fallthrough]];
    }
    case VIDIOC_G_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      const uint32_t bpp = bytes_per_pixel_of(fourcc_);
      f->fmt.pix.pixelformat = fourcc_;
      f->fmt.pix.width = width_;
      f->fmt.pix.height = height_;
      f->fmt.pix.field = V4L2_FIELD_NONE;
      f->fmt.pix.bytesperline = width_ * bpp;
      f->fmt.pix.sizeimage = bpp ? width_ * bpp * height_ : width_ * height_;
      return 0;
    }
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM: {
      auto* parm = static_cast<v4l2_streamparm*>(arg);
      if (!timeperframe) {
        if (request == VIDIOC_S_PARM) return -ENOTTY;
        parm->parm.capture = v4l2_captureparm{};
        return 0;
      }
      if (request == VIDIOC_S_PARM) timeperframe_ = parm->parm.capture.timeperframe;
      parm->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
      parm->parm.capture.timeperframe = timeperframe_;
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* req = static_cast<v4l2_requestbuffers*>(arg);
      if (req->memory != V4L2_MEMORY_MMAP) return -EINVAL;
      if (streaming_) return -EBUSY;
      for (const auto& b : buffers_) {
        if (b.mapped > 0 && req->count > 0) return -EBUSY;
      }
      for (auto& b : buffers_) {
        if (b.mapped > 0) orphans_.push_back(std::move(b));
      }
      buffers_.clear();
      incoming_.clear();
      done_order_.clear();
      if (req->count == 0) return 0;
      req->count = std::clamp<uint32_t>(req->count, 2, 8);
      const uint32_t bpp = bytes_per_pixel_of(fourcc_);
      const size_t size = bpp ? size_t{width_} * bpp * height_ : size_t{width_} * height_;
      buffers_.resize(req->count);
      for (uint32_t i = 0; i < req->count; ++i) {
        buffers_[i].memory.assign(size, 0);
        buffers_[i].info.index = i;
      }
      return 0;
    }
    case VIDIOC_QUERYBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= buffers_.size()) return -EINVAL;
      b->length = static_cast<uint32_t>(buffers_[b->index].memory.size());
      b->m.offset = b->index * kPage_bytes;
      return 0;
    }
    case VIDIOC_QBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= buffers_.size()) return -EINVAL;
      Buffer& buf = buffers_[b->index];
      if (buf.queued || buf.done) return -EINVAL;  // already owned by the driver
      buf.queued = true;
      incoming_.push_back(b->index);
      queue_order_.push_back(b->index);
      return 0;
    }
    case VIDIOC_DQBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (!streaming_) return -EINVAL;
      if (done_order_.empty()) return -EAGAIN;
      const uint32_t index = done_order_.front();
      const uint64_t frame = buffers_[index].info.reserved;
      if (auto it = dequeue_faults_.find(frame); it != dequeue_faults_.end()) {
        const auto [fault, error] = it->second;
        dequeue_faults_.erase(it);
        if (fault == Fault::kEagain) return -EAGAIN;
        if (error == ENODEV) {
          gone_ = true;
          fail_opens_ = reopen_failures_[frame];
        }
        return -error;
      }
      done_order_.erase(done_order_.begin());
      Buffer& buf = buffers_[index];
      buf.done = false;
      *b = buf.info;
      b->reserved = 0;
      b->index = index;
      b->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b->memory = V4L2_MEMORY_MMAP;
      dequeue_order_.push_back(index);
      return 0;
    }
    case VIDIOC_STREAMON:
      if (buffers_.empty()) return -EINVAL;
      streaming_ = true;
      return 0;
    case VIDIOC_STREAMOFF:
      streaming_ = false;
      for (auto& b : buffers_) b.queued = b.done = false;
      incoming_.clear();
      done_order_.clear();
      return 0;
    case VIDIOC_QUERYCTRL: {
      auto* q = static_cast<v4l2_queryctrl*>(arg);
      auto it = controls.find(q->id);
      if (it == controls.end()) return -EINVAL;
      q->minimum = it->second.minimum;
      q->maximum = it->second.maximum;
      q->flags = 0;
      return 0;
    }
    case VIDIOC_S_CTRL: {
      auto* c = static_cast<v4l2_control*>(arg);
      auto it = controls.find(c->id);
      if (it == controls.end()) return -EINVAL;
      if (c->value < it->second.minimum || c->value > it->second.maximum) return -ERANGE;
      it->second.value = c->value;
      return 0;
    }
    case VIDIOC_G_CTRL: {
      auto* c = static_cast<v4l2_control*>(arg);
      auto it = controls.find(c->id);
      if (it == controls.end()) return -EINVAL;
      c->value = it->second.value;
      return 0;
    }
    default:
      return -ENOTTY;
  }
}

}  // namespace ceilpose::capture::testing
