#include "capture/frame_source.h"

#include <spdlog/spdlog.h>

#include "capture/source_spec.h"
#include "capture/synthetic_source.h"
#include "capture/v4l2_source.h"
#ifdef CEILPOSE_CAPTURE_HAVE_RECORDING
#include "capture/replay_source.h"
#endif
#ifdef CEILPOSE_CAPTURE_HAVE_LIBCAMERA
#include "capture/libcamera_source.h"
#endif

namespace ceilpose::capture {

const char* to_string(NextStatus status) {
  switch (status) {
    case NextStatus::kFrame:
      return "frame";
    case NextStatus::kTimeout:
      return "timeout";
    case NextStatus::kEndOfStream:
      return "end of stream";
    case NextStatus::kError:
      return "error";
  }
  return "unknown";
}

FrameSource::~FrameSource() = default;

const char* FrameSource::state_name(State s) {
  switch (s) {
    case State::kClosed:
      return "Closed";
    case State::kOpen:
      return "Open";
    case State::kStreaming:
      return "Streaming";
  }
  return "unknown";
}

Result<void> FrameSource::require(State needed, const char* call) const {
  if (state_ == needed) return {};
  return make_error(describe() + ": " + call + " needs state " + state_name(needed) +
                    ", but the source is " + state_name(state_));
}

Result<void> FrameSource::open() {
  if (auto r = require(State::kClosed, "open()"); !r) return r;
  if (auto r = do_open(); !r) return r;
  state_ = State::kOpen;
  return {};
}

Result<void> FrameSource::start() {
  if (auto r = require(State::kOpen, "start()"); !r) return r;
  if (auto r = do_start(); !r) return r;
  state_ = State::kStreaming;
  return {};
}

NextStatus FrameSource::next(Frame* out, int timeout_ms) {
  if (state_ != State::kStreaming) {
    // A programming error, reported once rather than per call.
    if (!warned_next_state_) {
      spdlog::error("{}", require(State::kStreaming, "next()").error().message);
      warned_next_state_ = true;
    }
    return NextStatus::kError;
  }
  return do_next(out, timeout_ms);
}

void FrameSource::release(const Frame& frame) {
  if (state_ == State::kClosed) return;  // nothing can be held by a closed source
  do_release(frame);
}

void FrameSource::stop() {
  if (state_ != State::kStreaming) return;
  do_stop();
  state_ = State::kOpen;
}

namespace {

Error bad_spec(std::string_view spec, const std::string& why) {
  return make_error("Source '" + std::string(spec) + "': " + why + " (expected " +
                    std::string(kSourceSpecForms) + ")");
}

}  // namespace

Result<std::unique_ptr<FrameSource>> make_frame_source(std::string_view spec,
                                                       const SourceOptions& options,
                                                       std::shared_ptr<FrameGenerator> generator) {
  std::string why;
  const std::optional<SourceSpec> parsed = parse_source_spec(spec, &why);
  if (!parsed) return bad_spec(spec, why);
  switch (parsed->kind) {
    case SourceKind::kSynthetic:
      if (!generator) return bad_spec(spec, "the synthetic camera needs a frame generator");
      return std::unique_ptr<FrameSource>(
          std::make_unique<SyntheticSource>(options, std::move(generator)));
    case SourceKind::kReplay:
#ifdef CEILPOSE_CAPTURE_HAVE_RECORDING
      return std::unique_ptr<FrameSource>(
          std::make_unique<ReplaySource>(parsed->argument, options));
#else
      return bad_spec(spec, "this build has no recording reader (ceilpose_recording)");
#endif
    case SourceKind::kV4l2:
      return std::unique_ptr<FrameSource>(std::make_unique<V4l2Source>(parsed->argument, options));
    case SourceKind::kLibcamera:
#ifdef CEILPOSE_CAPTURE_HAVE_LIBCAMERA
      return std::unique_ptr<FrameSource>(
          std::make_unique<LibcameraSource>(parsed->argument, options));
#else
      return bad_spec(spec,
                      "this build has no libcamera backend (CEILPOSE_LIBCAMERA=OFF, or no "
                      "libcamera found when it was built; docs/arm64.md)");
#endif
  }
  return bad_spec(spec, "unknown source");
}

}  // namespace ceilpose::capture
