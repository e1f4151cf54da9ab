#include "capture/v4l2_source.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "capture/wait.h"
#include "core/clock.h"

namespace ceilpose::capture {
namespace {

uint32_t fourcc_of(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGray8:
      return V4L2_PIX_FMT_GREY;
    case PixelFormat::kRgb24:
      return V4L2_PIX_FMT_RGB24;
    case PixelFormat::kBgr24:
      return V4L2_PIX_FMT_BGR24;
    case PixelFormat::kYuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::kMjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case PixelFormat::kNv12:
      return V4L2_PIX_FMT_NV12;
    case PixelFormat::kYuv420:
      return V4L2_PIX_FMT_YUV420;
  }
  return 0;
}

std::string fourcc_text(uint32_t f) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) s[static_cast<size_t>(i)] = static_cast<char>((f >> (8 * i)) & 0xff);
  return s;
}

const char* err(int negative_errno) { return std::strerror(-negative_errno); }

int64_t timeval_ns(const timeval& tv) {
  return static_cast<int64_t>(tv.tv_sec) * 1'000'000'000 + static_cast<int64_t>(tv.tv_usec) * 1000;
}

}  // namespace

V4l2Source::V4l2Source(std::string device_path, SourceOptions options, V4l2Syscalls* sys)
    : path_(std::move(device_path)), options_(std::move(options)), sys_(sys) {}

V4l2Source::~V4l2Source() {
  stop_streaming();
  teardown_buffers();
  // Frames never released: unmap them now, the pipeline is gone with us.
  for (const auto& r : retired_) sys_->munmap(r.start, r.length);
  retired_.clear();
}

std::string V4l2Source::describe() const {
  if (width_ == 0) return "v4l2:" + path_ + " (not open)";
  char text[160];
  const char* stamps = !driver_timestamps_                            ? "dequeue-time stamps"
                       : stamp_event_ == StampEvent::kStartOfExposure ? "start-of-exposure stamps"
                                                                      : "end-of-frame stamps";
  std::snprintf(text, sizeof text,
                " %dx%d %s %.1f fps, %d buffers, %s, exposure %.1f ms, readout %.1f ms", width_,
                height_, to_string(format_), fps_, options_.buffer_count, stamps,
                static_cast<double>(exposure_ns_) * 1e-6, options_.readout_ms);
  return "v4l2:" + path_ + text;
}

// ---- open: device, capabilities, format, rate, controls ----

Result<void> V4l2Source::do_open() {
  if (auto r = open_device(); !r) return r;
  // Controls are best effort: a webcam without manual white balance still runs.
  lock_controls();
  return {};
}

Result<void> V4l2Source::open_device() {
  const int fd = sys_->open(path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return make_error("Failed to open " + path_ + ": " + err(fd));
  fd_ = UniqueFd(fd, sys_);
  if (auto r = query_capabilities(); !r) {
    fd_.reset();
    return r;
  }
  if (auto r = negotiate_format(); !r) {
    fd_.reset();
    return r;
  }
  set_frame_rate();
  return {};
}

Result<void> V4l2Source::query_capabilities() {
  v4l2_capability cap{};
  if (const int r = sys_->ioctl(fd_.get(), VIDIOC_QUERYCAP, &cap); r < 0) {
    return make_error("Failed to query capabilities of " + path_ +
                      " (is it a V4L2 device?): " + err(r));
  }
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    return make_error(path_ + " is not a single-planar video capture device (driver " +
                      reinterpret_cast<const char*>(cap.driver) + ")");
  }
  if (!(caps & V4L2_CAP_STREAMING)) {
    return make_error(path_ + " does not support streaming I/O (driver " +
                      reinterpret_cast<const char*>(cap.driver) + ")");
  }
  return {};
}

// Tries each preferred format in turn. A driver refuses a format either by
// failing S_FMT or, more often, by answering with a different pixelformat; both
// fall through to the next preference.
Result<void> V4l2Source::negotiate_format() {
  std::string tried;
  for (const PixelFormat want : options_.pixel_formats) {
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = static_cast<uint32_t>(options_.width);
    fmt.fmt.pix.height = static_cast<uint32_t>(options_.height);
    fmt.fmt.pix.pixelformat = fourcc_of(want);
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (!tried.empty()) tried += ", ";
    tried += to_string(want);
    const int r = sys_->ioctl(fd_.get(), VIDIOC_S_FMT, &fmt);
    if (r < 0) {
      if (r == -EBUSY || r == -ENODEV) {
        return make_error("Failed to set format " + std::string(to_string(want)) + " on " + path_ +
                          ": " + err(r));
      }
      tried += " (refused: " + std::string(err(r)) + ")";
      continue;
    }
    if (fmt.fmt.pix.pixelformat != fourcc_of(want)) {
      tried += " (driver offered " + fourcc_text(fmt.fmt.pix.pixelformat) + ")";
      continue;
    }
    format_ = want;
    fourcc_ = fmt.fmt.pix.pixelformat;
    width_ = static_cast<int>(fmt.fmt.pix.width);
    height_ = static_cast<int>(fmt.fmt.pix.height);
    stride_bytes_ = static_cast<int>(fmt.fmt.pix.bytesperline);
    if (want != PixelFormat::kMjpeg && stride_bytes_ < width_ * bytes_per_pixel(want)) {
      stride_bytes_ = width_ * bytes_per_pixel(want);
    }
    if (width_ != options_.width || height_ != options_.height) {
      spdlog::warn("{}: asked for {}x{}, driver gives {}x{} {}", path_, options_.width,
                   options_.height, width_, height_, to_string(want));
    }
    return {};
  }
  return make_error("No usable pixel format on " + path_ + "; tried " + tried);
}

void V4l2Source::set_frame_rate() {
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fps_ = options_.fps;
  if (sys_->ioctl(fd_.get(), VIDIOC_G_PARM, &parm) < 0 ||
      !(parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    spdlog::warn("{}: driver cannot set the frame rate; running at its default", path_);
    fps_ = 0.0;
    return;
  }
  // Frame interval as a fraction with ms resolution keeps 29.97-style rates.
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator =
      static_cast<uint32_t>(std::lround(options_.fps * 1000.0));
  if (const int r = sys_->ioctl(fd_.get(), VIDIOC_S_PARM, &parm); r < 0) {
    spdlog::warn("{}: Failed to set {} fps: {}", path_, options_.fps, err(r));
    return;
  }
  const auto& tpf = parm.parm.capture.timeperframe;
  if (tpf.numerator != 0) fps_ = static_cast<double>(tpf.denominator) / tpf.numerator;
  if (std::fabs(fps_ - options_.fps) > 0.01 * options_.fps) {
    spdlog::warn("{}: asked for {} fps, driver gives {:.2f} fps", path_, options_.fps, fps_);
  }
}

// Locks the controls that make colours drift (thesis: auto exposure and white
// balance ruined the colour thresholds). Missing controls are reported once,
// at the first open, not again on every reconnect.
void V4l2Source::lock_controls() {
  const ControlLocks& c = options_.controls;
  std::string missing;
  std::string locked;
  auto set = [&](uint32_t id, const char* name, int value, bool clamp) {
    v4l2_queryctrl q{};
    q.id = id;
    if (sys_->ioctl(fd_.get(), VIDIOC_QUERYCTRL, &q) < 0 || (q.flags & V4L2_CTRL_FLAG_DISABLED)) {
      missing += missing.empty() ? name : std::string(", ") + name;
      return false;
    }
    if (clamp) value = std::clamp(value, q.minimum, q.maximum);
    v4l2_control ctrl{id, value};
    if (const int r = sys_->ioctl(fd_.get(), VIDIOC_S_CTRL, &ctrl); r < 0) {
      if (!reported_controls_) {
        spdlog::warn("{}: Failed to set control {} to {}: {}", path_, name, value, err(r));
      }
      missing += missing.empty() ? name : std::string(", ") + name;
      return false;
    }
    locked += locked.empty() ? "" : ", ";
    locked += std::string(name) + "=" + std::to_string(value);
    return true;
  };
  if (c.lock_exposure) {
    set(V4L2_CID_EXPOSURE_AUTO, "exposure_auto", V4L2_EXPOSURE_MANUAL, false);
    // EXPOSURE_ABSOLUTE counts 100 µs units.
    set(V4L2_CID_EXPOSURE_ABSOLUTE, "exposure_absolute", std::max(1, c.exposure_us / 100), true);
  }
  if (c.lock_gain) {
    set(V4L2_CID_AUTOGAIN, "autogain", 0, false);
    if (c.gain >= 0) set(V4L2_CID_GAIN, "gain", c.gain, true);
  }
  if (c.lock_white_balance) {
    set(V4L2_CID_AUTO_WHITE_BALANCE, "white_balance_automatic", 0, false);
    set(V4L2_CID_WHITE_BALANCE_TEMPERATURE, "white_balance_temperature", c.white_balance_k, true);
  }
  if (!reported_controls_) {
    if (!locked.empty()) spdlog::info("{}: locked controls: {}", path_, locked);
    if (!missing.empty()) {
      spdlog::warn(
          "{}: cannot lock {} (control missing or refused); colours may drift with "
          "the lighting",
          path_, missing);
    }
    reported_controls_ = true;
  }
}

// ---- streaming ----

Result<void> V4l2Source::do_start() {
  if (auto r = start_streaming(); !r) return r;
  frames_since_exposure_read_ = 0;
  (void)exposure_ns();  // for the line below; re-read as frames come
  spdlog::info("{}: streaming {}", path_, describe());
  return {};
}

Result<void> V4l2Source::start_streaming() {
  v4l2_requestbuffers req{};
  req.count = static_cast<uint32_t>(options_.buffer_count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (const int r = sys_->ioctl(fd_.get(), VIDIOC_REQBUFS, &req); r < 0) {
    return make_error("Failed to request " + std::to_string(options_.buffer_count) +
                      " buffers on " + path_ + ": " + err(r));
  }
  if (req.count < 2) {
    return make_error("Driver of " + path_ + " granted only " + std::to_string(req.count) +
                      " buffer(s); streaming needs at least 2");
  }
  ++generation_;
  buffers_.assign(req.count, Buffer{});
  if (format_ == PixelFormat::kMjpeg) {
    decoded_.resize(req.count);
    for (auto& img : decoded_) img.resize(width_, height_, PixelFormat::kRgb24);
  }
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (const int r = sys_->ioctl(fd_.get(), VIDIOC_QUERYBUF, &buf); r < 0) {
      teardown_buffers();
      return make_error("Failed to query buffer " + std::to_string(i) + " on " + path_ + ": " +
                        err(r));
    }
    void* p = nullptr;
    if (const int r = sys_->mmap(fd_.get(), buf.length, buf.m.offset, &p); r < 0) {
      teardown_buffers();
      return make_error("Failed to map buffer " + std::to_string(i) + " (" +
                        std::to_string(buf.length) + " bytes) of " + path_ + ": " + err(r));
    }
    buffers_[i] = Buffer{p, buf.length, false};
  }
  for (uint32_t i = 0; i < req.count; ++i) {
    if (!queue_buffer(static_cast<int32_t>(i))) {
      teardown_buffers();
      return make_error("Failed to queue buffer " + std::to_string(i) + " on " + path_);
    }
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (const int r = sys_->ioctl(fd_.get(), VIDIOC_STREAMON, &type); r < 0) {
    teardown_buffers();
    return make_error("Failed to start streaming on " + path_ + ": " + err(r));
  }
  streaming_ = true;
  have_sequence_ = false;
  last_frame_ns_ = monotonic_ns();
  return {};
}

bool V4l2Source::queue_buffer(int32_t index) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  buf.index = static_cast<uint32_t>(index);
  const int r = sys_->ioctl(fd_.get(), VIDIOC_QBUF, &buf);
  if (r < 0) {
    // Logged here, with the buffer and device, because the caller is the
    // release path that has no error channel; this happens once per outage.
    spdlog::warn("Failed to queue buffer {} on {}: {}", index, path_, err(r));
    return false;
  }
  return true;
}

void V4l2Source::stop_streaming() {
  if (streaming_ && fd_.valid()) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    sys_->ioctl(fd_.get(), VIDIOC_STREAMOFF, &type);  // the device may be gone already
  }
  streaming_ = false;
}

// Unmaps the buffer set; buffers the pipeline still holds are retired instead
// and unmapped when released (a mapping outlives the fd it came from).
void V4l2Source::teardown_buffers() {
  for (size_t i = 0; i < buffers_.size(); ++i) {
    Buffer& b = buffers_[i];
    if (b.start == nullptr) continue;
    if (b.with_pipeline) {
      retired_.push_back({generation_, static_cast<int32_t>(i), b.start, b.length});
    } else {
      sys_->munmap(b.start, b.length);
    }
  }
  buffers_.clear();
  if (fd_.valid()) {
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    sys_->ioctl(fd_.get(), VIDIOC_REQBUFS, &req);  // count 0 frees the driver's buffers
  }
}

void V4l2Source::do_stop() {
  stop_streaming();
  teardown_buffers();
  if (recovering_) {
    recovering_ = false;
    fd_.reset();
  }
}

void V4l2Source::do_release(const Frame& frame) {
  if (frame.generation != generation_ || buffers_.empty()) {
    for (auto it = retired_.begin(); it != retired_.end(); ++it) {
      if (it->generation == frame.generation && it->index == frame.buffer_index) {
        sys_->munmap(it->start, it->length);
        retired_.erase(it);
        return;
      }
    }
    return;
  }
  if (frame.buffer_index < 0 || static_cast<size_t>(frame.buffer_index) >= buffers_.size()) return;
  Buffer& b = buffers_[static_cast<size_t>(frame.buffer_index)];
  b.with_pipeline = false;
  if (streaming_ && !recovering_ && !queue_buffer(frame.buffer_index)) {
    begin_outage("re-queueing a released buffer failed", 0);
  }
}

// ---- per frame ----

NextStatus V4l2Source::do_next(Frame* out, int timeout_ms) {
  const int64_t deadline_ns = monotonic_ns() + static_cast<int64_t>(timeout_ms) * 1'000'000;
  for (;;) {
    const int64_t now_ns = monotonic_ns();
    if (recovering_) {
      if (now_ns < next_attempt_ns_) {
        sleep_until_ns(std::min(next_attempt_ns_, deadline_ns));
        if (monotonic_ns() < next_attempt_ns_) return NextStatus::kTimeout;
      }
      if (!try_reconnect()) return NextStatus::kTimeout;
      continue;
    }
    // A stall is declared only after a poll that found nothing, so a caller
    // that was slow to come back is not mistaken for a silent device.
    const int64_t stall_at_ns =
        last_frame_ns_ + static_cast<int64_t>(options_.stall_timeout_ms) * 1'000'000;
    const int64_t wait_ns = std::max<int64_t>(0, std::min(deadline_ns, stall_at_ns) - now_ns);
    pollfd p{fd_.get(), POLLIN, 0};
    const int r = sys_->poll(&p, static_cast<int>((wait_ns + 999'999) / 1'000'000));
    if (r < 0) {
      if (r == -EINTR) continue;
      begin_outage("poll failed", r);
      continue;
    }
    if (r == 0) {
      const int64_t after_ns = monotonic_ns();
      if (after_ns >= stall_at_ns) {
        begin_outage("stalled: no frame within the stall timeout", 0);
        continue;
      }
      if (after_ns >= deadline_ns) return NextStatus::kTimeout;
      continue;
    }
    const NextStatus s = dequeue(out);
    if (s == NextStatus::kFrame) return s;
    if (s == NextStatus::kTimeout && (p.revents & (POLLERR | POLLHUP)) && !recovering_) {
      // An error flagged by poll with nothing to dequeue would spin; the
      // device is unusable until reopened.
      begin_outage("poll reports an error and no buffer is ready", 0);
    }
    // A stream of corrupt frames must not keep next() past its deadline.
    if (monotonic_ns() >= deadline_ns) return NextStatus::kTimeout;
  }
}

// The exposure time of the frames being dequeued, for their mid-exposure
// stamp: the driver's exposure_absolute (100 µs units; the locked value, or
// auto exposure's current one), re-read every kExposureRefreshFrames so that
// auto exposure is followed at a syscall per second. 0 when the driver has no
// such control (said once).
int64_t V4l2Source::exposure_ns() {
  if (frames_since_exposure_read_++ % kExposureRefreshFrames != 0) return exposure_ns_;
  v4l2_control ctrl{V4L2_CID_EXPOSURE_ABSOLUTE, 0};
  if (sys_->ioctl(fd_.get(), VIDIOC_G_CTRL, &ctrl) == 0 && ctrl.value > 0) {
    exposure_ns_ = int64_t{ctrl.value} * 100'000;
  } else {
    if (!warned_exposure_) {
      spdlog::info(
          "{}: no exposure_absolute control: frame times are the driver's stamps moved by "
          "half the readout only, not by half the (unknown) exposure",
          path_);
      warned_exposure_ = true;
    }
    exposure_ns_ = 0;
  }
  return exposure_ns_;
}

NextStatus V4l2Source::dequeue(Frame* out) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  const int r = sys_->ioctl(fd_.get(), VIDIOC_DQBUF, &buf);
  if (r < 0) {
    if (r != -EAGAIN) begin_outage("dequeueing a buffer failed", r);
    return NextStatus::kTimeout;
  }
  const int64_t dequeue_ns = monotonic_ns();
  if (buf.index >= buffers_.size()) {
    begin_outage("driver returned an unknown buffer index", 0);
    return NextStatus::kTimeout;
  }
  last_frame_ns_ = dequeue_ns;
  const int32_t index = static_cast<int32_t>(buf.index);
  if (have_sequence_ && buf.sequence > last_driver_sequence_ + 1) {
    stats_.drops += buf.sequence - last_driver_sequence_ - 1;
  }
  have_sequence_ = true;
  last_driver_sequence_ = buf.sequence;
  if (buf.flags & V4L2_BUF_FLAG_ERROR) {
    ++stats_.corrupt;
    if (!queue_buffer(index)) begin_outage("re-queueing a corrupt buffer failed", 0);
    return NextStatus::kTimeout;
  }

  Buffer& b = buffers_[static_cast<size_t>(index)];
  Frame f;
  if (format_ == PixelFormat::kMjpeg) {
    Image& img = decoded_[static_cast<size_t>(index)];
    // Into the buffer's RGB24 image at the negotiated size: a truncated,
    // corrupt or other-sized frame is counted, never half decoded.
    const auto decoded =
        jpeg_.decode_fixed(static_cast<const uint8_t*>(b.start), buf.bytesused, &img);
    if (!decoded) {
      ++stats_.corrupt;
      if (!queue_buffer(index)) begin_outage("re-queueing an undecodable buffer failed", 0);
      return NextStatus::kTimeout;
    }
    f.image = img.view();
  } else {
    f.image = ImageView{static_cast<const uint8_t*>(b.start),
                        width_,
                        height_,
                        stride_bytes_,
                        format_,
                        buf.bytesused};
  }
  // The driver stamps the start of exposure or the end of the frame (the
  // default); the frame's time is the centre row's mid-exposure.
  StampEvent event = (buf.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE
                         ? StampEvent::kStartOfExposure
                         : StampEvent::kEndOfFrame;
  int64_t stamp_ns = 0;
  if ((buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    stamp_ns = timeval_ns(buf.timestamp);
  } else {
    if (!warned_timestamps_) {
      // Once per source, not per frame.
      spdlog::warn(
          "{}: driver timestamps are not CLOCK_MONOTONIC; using dequeue time, "
          "which adds the queueing delay to every frame's age",
          path_);
      warned_timestamps_ = true;
    }
    driver_timestamps_ = false;
    stamp_ns = dequeue_ns;  // after the end of the frame, by the queueing delay
    event = StampEvent::kEndOfFrame;
  }
  stamp_event_ = event;
  f.capture_ns = exposure_mid_ns(stamp_ns, event, exposure_ns(), readout_ns_);
  f.dequeue_ns = dequeue_ns;
  f.source_timestamp_ns = f.capture_ns;
  f.sequence = sequence_++;
  f.buffer_index = index;
  f.generation = generation_;
  b.with_pipeline = true;
  ++stats_.frames;
  *out = f;
  return NextStatus::kFrame;
}

// ---- recovery ----

void V4l2Source::begin_outage(const char* what, int error) {
  if (recovering_) return;
  ++stats_.outages;
  recovering_ = true;
  outage_start_ns_ = monotonic_ns();
  backoff_ms_ = options_.reconnect_initial_ms;
  next_attempt_ns_ = outage_start_ns_ + static_cast<int64_t>(backoff_ms_) * 1'000'000;
  spdlog::warn("{}: outage #{}: {}{}{}; closing the device and reopening in {} ms", path_,
               stats_.outages, what, error < 0 ? ": " : "", error < 0 ? err(error) : "",
               backoff_ms_);
  stop_streaming();
  teardown_buffers();
  fd_.reset();
}

bool V4l2Source::try_reconnect() {
  Result<void> r = open_device();
  if (r) {
    lock_controls();
    r = start_streaming();
    if (!r) fd_.reset();
  }
  const int64_t now_ns = monotonic_ns();
  if (!r) {
    backoff_ms_ = std::min(backoff_ms_ * 2, options_.reconnect_max_ms);
    next_attempt_ns_ = now_ns + static_cast<int64_t>(backoff_ms_) * 1'000'000;
    spdlog::warn("{}: reopen failed: {}; next attempt in {} ms", path_, r.error().message,
                 backoff_ms_);
    return false;
  }
  recovering_ = false;
  ++stats_.reconnects;
  spdlog::info("{}: recovered after {} ms outage: {}", path_,
               (now_ns - outage_start_ns_) / 1'000'000, describe());
  return true;
}

}  // namespace ceilpose::capture
