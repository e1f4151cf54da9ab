#pragma once
// libcamera camera (libcamera or libcamera:ID): picks the camera (the first
// one, or the one whose id matches), configures one VideoRecording stream at
// the requested size in the preferred pixel format, locks auto exposure and
// auto white balance when the camera offers those controls, and delivers each
// completed request's buffer (mmap'd once at start, zero-copy) with the
// sensor timestamp. With no camera it fails in open() and says so.
//
// libcamera completes requests on its own thread; they wait in a small queue
// (mutex + condition variable, the one lock on this path) until next() takes
// them. Device-loss recovery is not implemented for this backend: a
// disconnected camera ends the stream with kError.
//
// Threads: see FrameSource; one thread (the capture thread) only.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "capture/frame_source.h"

namespace libcamera {
class Camera;
class CameraManager;
class FrameBufferAllocator;
class Request;
class Stream;
}  // namespace libcamera

namespace ceilpose::capture {

class LibcameraSource final : public FrameSource {
 public:
  // Stores the configuration; cannot fail. An empty id picks the first camera.
  LibcameraSource(std::string camera_id, SourceOptions options);
  ~LibcameraSource() override;

  std::string describe() const override;
  SourceStats stats() const override { return stats_; }
  int buffers() const override { return static_cast<int>(requests_.size()); }

 protected:
  Result<void> do_open() override;
  Result<void> do_start() override;
  NextStatus do_next(Frame* out, int timeout_ms) override;
  void do_release(const Frame& frame) override;
  void do_stop() override;

 private:
  struct Mapping {
    void* start = nullptr;
    size_t length = 0;
    size_t offset = 0;  // of plane 0 inside the mapping
  };
  Result<void> open_camera();
  void close_camera();
  void on_request_completed(libcamera::Request* request);
  void unmap_all();

  const std::string camera_id_;
  const SourceOptions options_;
  std::unique_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  libcamera::Stream* stream_ = nullptr;
  std::vector<std::unique_ptr<libcamera::Request>> requests_;
  std::vector<Mapping> mappings_;
  PixelFormat format_ = PixelFormat::kRgb24;
  int width_ = 0;
  int height_ = 0;
  int stride_bytes_ = 0;
  bool acquired_ = false;
  bool started_ = false;

  std::mutex mutex_;
  std::condition_variable completed_cv_;
  std::deque<libcamera::Request*> completed_;  // sized to the request count at start
  bool camera_failed_ = false;

  uint64_t sequence_ = 0;
  SourceStats stats_;
};

}  // namespace ceilpose::capture
