#pragma once
// FrameSource: the one interface every camera backend implements (V4L2,
// libcamera, replay of a SPEC §4 recording, the simulator as a live camera).
//
// Modelled on libcamera's V4L2VideoDevice: constructing a source only stores
// its configuration and cannot fail; the work (and every error) is in open()
// and start(). The base class owns the lifecycle state so that every backend
// checks it the same way; backends implement the do_*() hooks.
//
// State machine (the only drawing of it):
//
//   ┌────────┐  open()   ┌──────┐  start()   ┌───────────┐ ──┐ next(), release(),
//   │ Closed │ ────────▶ │ Open │ ─────────▶ │ Streaming │   │ device loss and
//   └────────┘           └──────┘ ◀───────── └───────────┘ ◀─┘ recovery
//        ▲                  │        stop()
//        └─ ~FrameSource() ─┘   (the destructor stops and closes from any state)
//
// A failed open() leaves the source Closed and a failed start() leaves it
// Open, so either may be retried. release() is accepted in Open and Streaming
// (frames still held by the pipeline after stop() come back that way).
//
// Threads: construction and describe() from any thread; every other call from
// one thread at a time, in practice the capture thread (CaptureThread calls
// open() and start() on its own thread too).
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "capture/frame.h"
#include "core/camera_model.h"
#include "core/frame_generator.h"
#include "core/result.h"

namespace ceilpose::capture {

// Camera controls the thesis found must not float: auto exposure, auto gain and
// auto white balance move the colours its thresholds depend on.
struct ControlLocks {
  bool lock_exposure = true;
  int exposure_us = 8000;  // manual exposure time; short to limit motion blur
  bool lock_gain = true;
  int gain = -1;  // driver units; -1 keeps the driver's current value
  bool lock_white_balance = true;
  int white_balance_k = 4600;  // colour temperature; typical office fluorescent light
};

struct SourceOptions {
  // Requested image geometry and rate; a V4L2 driver may adjust them and the
  // source reports what was negotiated (describe()).
  // (ceilposed asks for camera.width x camera.height, the calibrated size.)
  int width = 640;
  int height = 480;
  double fps = 30.0;
  // V4L2 pixel formats in order of preference; a refused one falls through to
  // the next. YUYV first: raw, zero-copy and cheap to threshold; then the
  // 4:2:0 formats of ISPs and Pi cameras, read natively too.
  std::vector<PixelFormat> pixel_formats{PixelFormat::kYuyv,   PixelFormat::kNv12,
                                         PixelFormat::kYuv420, PixelFormat::kRgb24,
                                         PixelFormat::kBgr24,  PixelFormat::kMjpeg};
  // Driver buffers (V4L2 mmap, libcamera) or frame slots (replay, synthetic).
  // The pipeline holds one, the ring a few, the driver needs at least one.
  int buffer_count = 4;
  ControlLocks controls;
  // Rolling-shutter readout, first row to last, milliseconds (camera.readout_ms;
  // 0 = global shutter): live sources stamp frames at the centre row's
  // mid-exposure (capture/exposure_timing.h).
  double readout_ms = 0.0;

  // Recovery of live devices: no frame for stall_timeout_ms counts as a stall;
  // reopen attempts back off exponentially from reconnect_initial_ms up to
  // reconnect_max_ms.
  int stall_timeout_ms = 2000;
  int reconnect_initial_ms = 100;
  int reconnect_max_ms = 5000;

  // Replay: pace by the recorded timestamps divided by replay_speed (1 =
  // recorded timing, 2 = twice as fast), or with 0 deliver as fast as the
  // consumer takes frames (lossless); optionally loop forever.
  double replay_speed = 1.0;
  bool replay_loop = false;
};

class FrameSource {
 public:
  virtual ~FrameSource();
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;

  // Closed -> Open: finds and opens the device or recording and negotiates the
  // format. Errors name the device or file.
  Result<void> open();
  // Open -> Streaming.
  Result<void> start();
  // Streaming: waits at most timeout_ms for the next frame. No allocation, no
  // exception, no logging per frame; a live source recovers from device loss
  // inside next() and returns kTimeout meanwhile.
  NextStatus next(Frame* out, int timeout_ms);
  // Hands a frame from next() back to the source (for V4L2: re-queues it).
  void release(const Frame& frame);
  // Streaming -> Open; harmless in Open. Frames not yet released stay valid.
  void stop();

  // "v4l2:/dev/video0 640x480 YUYV 30 fps, 4 buffers", for logs and status.
  virtual std::string describe() const = 0;
  virtual SourceStats stats() const = 0;
  // False for a source that runs as fast as it is consumed (fast replay); the
  // capture thread then waits for the pipeline instead of dropping frames.
  virtual bool live() const { return true; }
  // Buffers (slots) the source cycles through; valid once streaming. At most
  // this many frames can be held outside the source at once.
  virtual int buffers() const = 0;
  // The camera model when the source knows it (the simulator's camera, a
  // recording's recording.yaml); false for cameras (calibration is the
  // configuration's job). Valid once open.
  virtual bool camera_intrinsics(CameraIntrinsics* /*out*/) const { return false; }

 protected:
  FrameSource() = default;
  virtual Result<void> do_open() = 0;
  virtual Result<void> do_start() = 0;
  virtual NextStatus do_next(Frame* out, int timeout_ms) = 0;
  virtual void do_release(const Frame& frame) = 0;
  virtual void do_stop() = 0;

 private:
  enum class State { kClosed, kOpen, kStreaming };
  static const char* state_name(State s);
  Result<void> require(State needed, const char* call) const;

  State state_ = State::kClosed;
  bool warned_next_state_ = false;
};

// SPEC §7 source spec: synthetic | replay:DIR | v4l2:/dev/videoN | libcamera[:ID].
// The returned source is Closed; an unknown spec, a backend not built in, or
// "synthetic" without a `generator` (what renders its images) is an error
// naming the spec.
Result<std::unique_ptr<FrameSource>> make_frame_source(
    std::string_view spec, const SourceOptions& options,
    std::shared_ptr<FrameGenerator> generator = nullptr);

}  // namespace ceilpose::capture
