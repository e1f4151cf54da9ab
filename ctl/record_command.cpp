// ceilposectl record: writes a SPEC §4 recording from any frame source
// (synthetic, replay:DIR, v4l2:/dev/videoN, libcamera[:ID]). The synthetic
// source writes its ground truth; replay keeps the recorded timestamps and
// ground truth; live cameras write CLOCK_MONOTONIC capture times.
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "capture/frame_source.h"
#include "capture/pixel_convert.h"
#include "capture/source_spec.h"
#include "core/clock.h"
#include "ctl/command_registry.h"
#include "recording/recording_writer.h"
#include "sim/trajectory_camera.h"

namespace ceilpose::ctl {
namespace {

struct RecordArgs {
  std::string source;
  std::string out_dir;
  int64_t frames = 0;
  double duration_s = 0.0;
  int width = 640;
  int height = 480;
  double fps = 30.0;
  double readout_ms = 0.0;  // a live camera's rolling-shutter readout (SPEC §3)
  int jpeg_quality = 0;
  uint64_t seed = 1;
  bool realtime_replay = false;
};

// SPEC §3's default camera scaled to the delivered size: an uncalibrated
// camera's best guess, said so in recording.yaml's source text.
CameraIntrinsics scaled_default(int width, int height) {
  CameraIntrinsics k;
  const double s = static_cast<double>(width) / k.width;
  k.fx *= s;
  k.fy *= s;
  k.cx = (width - 1) * 0.5;
  k.cy = (height - 1) * 0.5;
  k.width = width;
  k.height = height;
  return k;
}

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "ceilposectl record: %s\n", message.c_str());
  return code;
}

// Makes, opens and starts the source --source names; prints why and sets *rc
// when it cannot.
std::unique_ptr<capture::FrameSource> start_source(const RecordArgs& a, bool replay, int* rc) {
  capture::SourceOptions options;
  options.width = a.width;
  options.height = a.height;
  options.fps = a.fps;
  options.readout_ms = a.readout_ms;
  if (!a.realtime_replay) options.replay_speed = 0.0;  // as fast as possible
  std::shared_ptr<FrameGenerator> generator;
  if (capture::is_synthetic_spec(a.source)) {
    sim::TrajectoryCameraOptions camera;
    camera.scene.seed = a.seed;
    generator = std::make_shared<sim::TrajectoryCamera>(camera);
  }
  auto made = capture::make_frame_source(a.source, options, std::move(generator));
  if (!made) {
    *rc = fail(kExitUsage, made.error().message);
    return nullptr;
  }
  std::unique_ptr<capture::FrameSource> source = std::move(made).value();
  if (auto r = source->open(); !r) {
    *rc = fail(replay ? kExitBadInput : kExitFailure, r.error().message);
    return nullptr;
  }
  if (auto r = source->start(); !r) {
    *rc = fail(kExitFailure, r.error().message);
    return nullptr;
  }
  return source;
}

// Writes the frames of one source to --out: the writer is created at the
// first frame (a driver may adjust the size), YUYV is converted to RGB.
class FrameRecorder {
 public:
  FrameRecorder(const RecordArgs& a, const capture::FrameSource& source) : a_(a), source_(source) {}

  // kExitOk, or the exit code after printing why.
  int write(const capture::Frame& frame) {
    if (!writer_) {
      RecordingCamera camera;
      if (source_.camera_intrinsics(&camera.intrinsics)) {
        camera.source = source_.describe();
      } else {
        camera.intrinsics = scaled_default(frame.image.width, frame.image.height);
        camera.intrinsics.readout_ms = a_.readout_ms;
        camera.source = source_.describe() + "; uncalibrated: SPEC default intrinsics scaled";
      }
      auto w = RecordingWriter::create(a_.out_dir, camera);
      if (!w) return fail(kExitFailure, w.error().message);
      writer_.emplace(std::move(w).value());
    }
    ImageView view = frame.image;
    // Recordings store RGB, grey or the camera's JPEG (SPEC §4).
    if (view.format == PixelFormat::kYuyv || is_yuv420(view.format)) {
      if (auto r = capture::to_rgb24(view, &converted_); !r)
        return fail(kExitFailure, r.error().message);
      view = converted_.view();
    }
    auto r =
        writer_->append(view, frame.source_timestamp_ns,
                        frame.has_ground_truth ? &frame.ground_truth : nullptr, a_.jpeg_quality);
    if (!r) return fail(kExitFailure, r.error().message);
    ++written_;
    return kExitOk;
  }

  // Closes the recording; `rc` unless closing fails.
  int close(int rc) {
    if (writer_) {
      if (auto r = writer_->close(); !r && rc == kExitOk)
        rc = fail(kExitFailure, r.error().message);
    }
    return rc;
  }

  int64_t written() const { return written_; }

 private:
  const RecordArgs& a_;
  const capture::FrameSource& source_;
  std::optional<RecordingWriter> writer_;
  Image converted_;
  int64_t written_ = 0;
};

int run_record(const RecordArgs& a) {
  const bool replay = capture::is_replay_spec(a.source);
  if (a.frames <= 0 && a.duration_s <= 0.0 && !replay) {
    return fail(kExitUsage, "a live source needs --frames N or --duration S");
  }
  int rc = kExitOk;
  std::unique_ptr<capture::FrameSource> source = start_source(a, replay, &rc);
  if (!source) return rc;
  std::fprintf(stderr, "record: %s -> %s\n", source->describe().c_str(), a.out_dir.c_str());

  FrameRecorder recorder(a, *source);
  capture::Frame frame;
  const int64_t start_ns = monotonic_ns();
  const int64_t end_ns =
      a.duration_s > 0.0 ? start_ns + static_cast<int64_t>(std::llround(a.duration_s * 1e9)) : 0;
  int64_t next_progress_ns = start_ns + 1'000'000'000;
  bool progress_shown = false;
  while (rc == kExitOk) {
    if (a.frames > 0 && recorder.written() >= a.frames) break;
    if (end_ns != 0 && monotonic_ns() >= end_ns) break;
    const capture::NextStatus s = source->next(&frame, 100);
    if (s == capture::NextStatus::kEndOfStream) break;
    if (s == capture::NextStatus::kError) {
      rc = fail(replay ? kExitBadInput : kExitFailure, source->describe() + ": source failed");
      break;
    }
    if (s == capture::NextStatus::kTimeout) continue;
    rc = recorder.write(frame);
    source->release(frame);
    const int64_t now_ns = monotonic_ns();
    if (now_ns >= next_progress_ns) {
      const auto st = source->stats();
      std::fprintf(stderr, "record: %lld frames, %.1f fps, %llu dropped, %llu outages\r",
                   static_cast<long long>(recorder.written()),
                   recorder.written() * 1e9 / (now_ns - start_ns),
                   static_cast<unsigned long long>(st.drops),
                   static_cast<unsigned long long>(st.outages));
      next_progress_ns = now_ns + 1'000'000'000;
      progress_shown = true;
    }
  }
  source->stop();
  rc = recorder.close(rc);
  const auto st = source->stats();
  if (progress_shown) std::fputc('\n', stderr);  // end the \r progress line
  std::fprintf(stderr, "record: %lld frames written to %s; %llu dropped, %llu outages\n",
               static_cast<long long>(recorder.written()), a.out_dir.c_str(),
               static_cast<unsigned long long>(st.drops),
               static_cast<unsigned long long>(st.outages));
  if (rc == kExitOk && recorder.written() == 0) rc = fail(kExitFailure, "no frame was captured");
  return rc;
}

void add_record_command(CLI::App& app) {
  auto args = std::make_shared<RecordArgs>();
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Write a SPEC §4 recording from a frame source: synthetic (with ground truth), "
      "replay:DIR (re-records, as fast as possible unless --realtime), v4l2:/dev/videoN or "
      "libcamera[:ID] (exposure, gain and white balance locked). Progress on stderr. Exit 1 "
      "when the source or the writer fails, 2 on a bad command line, 4 when a replayed "
      "recording is malformed.");
  cmd->add_option("--source", args->source, std::string(capture::kSourceSpecForms))->required();
  cmd->add_option("--out", args->out_dir,
                  "Recording directory to create (must not exist or be empty)")
      ->required();
  auto* frames =
      cmd->add_option("--frames", args->frames, "Stop after N frames")->check(CLI::PositiveNumber);
  cmd->add_option("--duration", args->duration_s, "Stop after S seconds")
      ->check(CLI::PositiveNumber)
      ->excludes(frames);
  cmd->add_option("--width", args->width, "Requested width of a camera (default 640)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--height", args->height, "Requested height of a camera (default 480)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--fps", args->fps, "Frame rate of a camera or the synthetic source (default 30)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--readout-ms", args->readout_ms,
                  "A live camera's rolling-shutter readout, first row to last, ms (SPEC §3): "
                  "frames are stamped at the centre row and recording.yaml declares it "
                  "(default 0, a global shutter)")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--jpeg-quality", args->jpeg_quality,
                  "Write JPEG frames at this quality (1..100) instead of PNG")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--seed", args->seed, "Synthetic scene seed (fixtures, clutter, noise)");
  cmd->add_flag("--realtime", args->realtime_replay,
                "Pace a replay source by its recorded timestamps instead of as fast as possible");
  cmd->callback([args] { set_exit_code(run_record(*args)); });
}

const CommandRegistrar kRecordRegistrar{"record", &add_record_command};

}  // namespace
}  // namespace ceilpose::ctl
