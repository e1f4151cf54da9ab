#include "capture/libcamera_source.h"

#include <libcamera/libcamera.h>
#include <spdlog/spdlog.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

#include "capture/exposure_timing.h"
#include "core/clock.h"

namespace ceilpose::capture {
namespace {

namespace lc = libcamera;

// libcamera names packed formats by their DRM fourcc, little-endian word
// order: formats::BGR888 is R, G, B bytes in memory, i.e. our RGB24.
bool to_libcamera(PixelFormat f, lc::PixelFormat* out) {
  switch (f) {
    case PixelFormat::kRgb24:
      *out = lc::formats::BGR888;
      return true;
    case PixelFormat::kBgr24:
      *out = lc::formats::RGB888;
      return true;
    case PixelFormat::kYuyv:
      *out = lc::formats::YUYV;
      return true;
    case PixelFormat::kGray8:
      *out = lc::formats::R8;
      return true;
    case PixelFormat::kNv12:
      *out = lc::formats::NV12;
      return true;
    case PixelFormat::kYuv420:
      *out = lc::formats::YUV420;
      return true;
    case PixelFormat::kMjpeg:
      return false;  // not offered by libcamera pipelines we target
  }
  return false;
}

}  // namespace

LibcameraSource::LibcameraSource(std::string camera_id, SourceOptions options)
    : camera_id_(std::move(camera_id)), options_(std::move(options)) {}

LibcameraSource::~LibcameraSource() {
  do_stop();
  close_camera();
}

// Releases everything open() and start() took, so that a failed open() can be
// retried: libcamera allows only one CameraManager per process at a time.
void LibcameraSource::close_camera() {
  unmap_all();
  requests_.clear();
  allocator_.reset();
  if (acquired_) camera_->release();
  acquired_ = false;
  camera_.reset();
  if (manager_) manager_->stop();
  manager_.reset();
  stream_ = nullptr;
}

std::string LibcameraSource::describe() const {
  std::string name = camera_id_.empty() ? "libcamera" : "libcamera:" + camera_id_;
  if (width_ == 0) return name + " (not open)";
  return name + " " + std::to_string(width_) + "x" + std::to_string(height_) + " " +
         to_string(format_) + ", " + std::to_string(requests_.size()) + " buffers";
}

Result<void> LibcameraSource::do_open() {
  Result<void> r = open_camera();
  if (!r) close_camera();
  return r;
}

Result<void> LibcameraSource::open_camera() {
  const std::string name = camera_id_.empty() ? "libcamera" : "libcamera:" + camera_id_;
  manager_ = std::make_unique<lc::CameraManager>();
  if (const int r = manager_->start(); r < 0) {
    manager_.reset();  // never started, so not to be stopped
    return make_error(name +
                      ": Failed to start the libcamera camera manager: " + std::strerror(-r));
  }
  const auto cameras = manager_->cameras();
  if (cameras.empty()) {
    return make_error(name +
                      ": no camera found (libcamera lists 0 cameras; is one connected "
                      "and supported by a libcamera pipeline handler?)");
  }
  if (camera_id_.empty()) {
    camera_ = cameras.front();
  } else {
    camera_ = manager_->get(camera_id_);
    if (!camera_) {
      std::string ids;
      for (const auto& c : cameras) ids += (ids.empty() ? "" : ", ") + c->id();
      return make_error(name + ": no camera with this id; libcamera has: " + ids);
    }
  }
  if (const int r = camera_->acquire(); r < 0) {
    return make_error(name + ": Failed to acquire camera " + camera_->id() + ": " +
                      std::strerror(-r));
  }
  acquired_ = true;

  auto config = camera_->generateConfiguration({lc::StreamRole::VideoRecording});
  if (!config || config->size() != 1) {
    return make_error(name + ": camera " + camera_->id() + " offers no video stream");
  }
  lc::StreamConfiguration& sc = config->at(0);
  sc.size = lc::Size(static_cast<unsigned>(options_.width), static_cast<unsigned>(options_.height));
  sc.bufferCount = static_cast<unsigned>(options_.buffer_count);
  bool chosen = false;
  for (const PixelFormat want : options_.pixel_formats) {
    lc::PixelFormat pf;
    if (!to_libcamera(want, &pf)) continue;
    sc.pixelFormat = pf;
    if (config->validate() == lc::CameraConfiguration::Invalid) continue;
    if (sc.pixelFormat == pf) {
      format_ = want;
      chosen = true;
      break;
    }
  }
  if (!chosen) {
    return make_error(name + ": camera " + camera_->id() +
                      " offers none of the preferred pixel formats (offers " +
                      sc.pixelFormat.toString() + ")");
  }
  if (const int r = camera_->configure(config.get()); r < 0) {
    return make_error(name + ": Failed to configure camera " + camera_->id() + " for " +
                      sc.toString() + ": " + std::strerror(-r));
  }
  stream_ = sc.stream();
  width_ = static_cast<int>(sc.size.width);
  height_ = static_cast<int>(sc.size.height);
  stride_bytes_ = static_cast<int>(sc.stride);
  return {};
}

Result<void> LibcameraSource::do_start() {
  const std::string name = describe();
  allocator_ = std::make_unique<lc::FrameBufferAllocator>(camera_);
  if (const int r = allocator_->allocate(stream_); r < 0) {
    return make_error(name + ": Failed to allocate buffers: " + std::strerror(-r));
  }
  const auto& buffers = allocator_->buffers(stream_);
  requests_.clear();
  mappings_.clear();
  for (size_t i = 0; i < buffers.size(); ++i) {
    const lc::FrameBuffer::Plane& plane = buffers[i]->planes()[0];
    // The detector reads a 4:2:0 frame's chroma planes right after the luma
    // (core/image.h), as one contiguous mapping of one buffer.
    size_t expected_offset = plane.offset;
    size_t map_length = plane.offset + plane.length;
    for (const lc::FrameBuffer::Plane& other : buffers[i]->planes()) {
      if (other.fd.get() != plane.fd.get() || other.offset != expected_offset) {
        return make_error(name + ": the " + to_string(format_) +
                          " buffer's planes are not contiguous in one buffer; use "
                          "capture.pixel_format yuyv or rgb24");
      }
      expected_offset = other.offset + other.length;
      map_length = std::max(map_length, static_cast<size_t>(other.offset + other.length));
    }
    void* p = mmap(nullptr, map_length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
    if (p == MAP_FAILED) {
      unmap_all();
      return make_error(name + ": Failed to map buffer " + std::to_string(i) + ": " +
                        std::strerror(errno));
    }
    mappings_.push_back({p, map_length, plane.offset});
    auto request = camera_->createRequest(i);
    if (!request || request->addBuffer(stream_, buffers[i].get()) < 0) {
      unmap_all();
      return make_error(name + ": Failed to create a request for buffer " + std::to_string(i));
    }
    requests_.push_back(std::move(request));
  }
  lc::ControlList controls(lc::controls::controls);
  const auto& info = camera_->controls();
  const ControlLocks& c = options_.controls;
  if (c.lock_exposure && info.count(&lc::controls::AeEnable)) {
    controls.set(lc::controls::AeEnable, false);
    if (info.count(&lc::controls::ExposureTime)) {
      controls.set(lc::controls::ExposureTime, static_cast<int32_t>(c.exposure_us));
    }
  } else if (c.lock_exposure) {
    spdlog::warn("{}: cannot lock exposure (no AeEnable control); colours may drift", name);
  }
  if (c.lock_white_balance && info.count(&lc::controls::AwbEnable)) {
    controls.set(lc::controls::AwbEnable, false);
  } else if (c.lock_white_balance) {
    spdlog::warn("{}: cannot lock white balance (no AwbEnable control); colours may drift", name);
  }
  camera_->requestCompleted.connect(this, &LibcameraSource::on_request_completed);
  if (const int r = camera_->start(&controls); r < 0) {
    return make_error(name + ": Failed to start camera: " + std::strerror(-r));
  }
  started_ = true;
  for (auto& request : requests_) {
    if (const int r = camera_->queueRequest(request.get()); r < 0) {
      return make_error(name + ": Failed to queue a request: " + std::strerror(-r));
    }
  }
  return {};
}

// libcamera's thread.
void LibcameraSource::on_request_completed(lc::Request* request) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (request->status() == lc::Request::RequestCancelled) return;
    completed_.push_back(request);
  }
  completed_cv_.notify_one();
}

NextStatus LibcameraSource::do_next(Frame* out, int timeout_ms) {
  lc::Request* request = nullptr;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!completed_cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                                [&] { return !completed_.empty() || camera_failed_; })) {
      return NextStatus::kTimeout;
    }
    if (camera_failed_) return NextStatus::kError;
    request = completed_.front();
    completed_.pop_front();
  }
  const int64_t dequeue_ns = monotonic_ns();
  const size_t index = static_cast<size_t>(request->cookie());
  const lc::FrameBuffer* buffer = request->findBuffer(stream_);
  const Mapping& m = mappings_[index];
  Frame f;
  f.image = ImageView{
      static_cast<const uint8_t*>(m.start) + m.offset, width_, height_, stride_bytes_, format_,
      frame_bytes(format_, stride_bytes_, height_)};
  // SensorTimestamp marks the first row's readout on CLOCK_BOOTTIME; the
  // buffer's own timestamp (pipelines without it) is the V4L2 end-of-frame
  // stamp on CLOCK_MONOTONIC. Either becomes the centre row's mid-exposure.
  const lc::ControlList& meta = request->metadata();
  const auto sensor_ns = meta.get(lc::controls::SensorTimestamp);
  const auto exposure_us = meta.get(lc::controls::ExposureTime);
  const int64_t exposure_ns = exposure_us ? int64_t{*exposure_us} * 1000 : 0;
  const int64_t readout_ns = std::llround(options_.readout_ms * 1e6);
  f.capture_ns = sensor_ns ? exposure_mid_ns(*sensor_ns - boottime_minus_monotonic_ns(),
                                             StampEvent::kStartOfFrame, exposure_ns, readout_ns)
                           : exposure_mid_ns(static_cast<int64_t>(buffer->metadata().timestamp),
                                             StampEvent::kEndOfFrame, exposure_ns, readout_ns);
  f.dequeue_ns = dequeue_ns;
  f.source_timestamp_ns = f.capture_ns;
  f.sequence = sequence_++;
  f.buffer_index = static_cast<int32_t>(index);
  ++stats_.frames;
  *out = f;
  return NextStatus::kFrame;
}

void LibcameraSource::do_release(const Frame& frame) {
  if (!started_ || frame.buffer_index < 0 ||
      static_cast<size_t>(frame.buffer_index) >= requests_.size()) {
    return;
  }
  lc::Request* request = requests_[static_cast<size_t>(frame.buffer_index)].get();
  request->reuse(lc::Request::ReuseBuffers);
  if (camera_->queueRequest(request) < 0) {
    std::lock_guard<std::mutex> lock(mutex_);
    camera_failed_ = true;
  }
}

void LibcameraSource::do_stop() {
  if (!started_) return;
  camera_->stop();
  camera_->requestCompleted.disconnect(this, &LibcameraSource::on_request_completed);
  started_ = false;
  std::lock_guard<std::mutex> lock(mutex_);
  completed_.clear();
}

void LibcameraSource::unmap_all() {
  for (const auto& m : mappings_) munmap(m.start, m.length);
  mappings_.clear();
}

}  // namespace ceilpose::capture
