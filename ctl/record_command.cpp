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

int run_record(const RecordArgs& a) {
  const bool replay = capture::is_replay_spec(a.source);
  if (a.frames <= 0 && a.duration_s <= 0.0 && !replay) {
    return fail(kExitUsage, "a live source needs --frames N or --duration S");
  }
  capture::SourceOptions options;
  options.width = a.width;
  options.height = a.height;
  options.fps = a.fps;
  if (!a.realtime_replay) options.replay_speed = 0.0;  // as fast as possible
  std::shared_ptr<FrameGenerator> generator;
  if (capture::is_synthetic_spec(a.source)) {
    sim::TrajectoryCameraOptions camera;
    camera.scene.seed = a.seed;
    generator = std::make_shared<sim::TrajectoryCamera>(camera);
  }
  auto made = capture::make_frame_source(a.source, options, std::move(generator));
  if (!made) return fail(kExitUsage, made.error().message);
  capture::FrameSource& source = **made;
  if (auto r = source.open(); !r)
    return fail(replay ? kExitBadInput : kExitFailure, r.error().message);
  if (auto r = source.start(); !r) return fail(kExitFailure, r.error().message);
  std::fprintf(stderr, "record: %s -> %s\n", source.describe().c_str(), a.out_dir.c_str());

  std::optional<RecordingWriter> writer;
  capture::Frame frame;
  Image converted;
  int64_t written = 0;
  const int64_t start_ns = monotonic_ns();
  const int64_t end_ns =
      a.duration_s > 0.0 ? start_ns + static_cast<int64_t>(std::llround(a.duration_s * 1e9)) : 0;
  int64_t next_progress_ns = start_ns + 1'000'000'000;
  bool progress_shown = false;
  int rc = kExitOk;
  for (;;) {
    if (a.frames > 0 && written >= a.frames) break;
    if (end_ns != 0 && monotonic_ns() >= end_ns) break;
    const capture::NextStatus s = source.next(&frame, 100);
    if (s == capture::NextStatus::kEndOfStream) break;
    if (s == capture::NextStatus::kError) {
      rc = fail(replay ? kExitBadInput : kExitFailure, source.describe() + ": source failed");
      break;
    }
    if (s == capture::NextStatus::kTimeout) continue;
    if (!writer) {
      // The size is known only from the first frame (a driver may adjust it).
      RecordingCamera camera;
      if (source.camera_intrinsics(&camera.intrinsics)) {
        camera.source = source.describe();
      } else {
        camera.intrinsics = scaled_default(frame.image.width, frame.image.height);
        camera.source = source.describe() + "; uncalibrated: SPEC default intrinsics scaled";
      }
      auto w = RecordingWriter::create(a.out_dir, camera);
      if (!w) {
        source.release(frame);
        rc = fail(kExitFailure, w.error().message);
        break;
      }
      writer.emplace(std::move(w).value());
    }
    ImageView view = frame.image;
    if (view.format == PixelFormat::kYuyv) {
      if (auto r = capture::to_rgb24(view, &converted); !r) {
        source.release(frame);
        rc = fail(kExitFailure, r.error().message);
        break;
      }
      view = converted.view();
    }
    auto r = writer->append(view, frame.source_timestamp_ns,
                            frame.has_ground_truth ? &frame.ground_truth : nullptr, a.jpeg_quality);
    source.release(frame);
    if (!r) {
      rc = fail(kExitFailure, r.error().message);
      break;
    }
    ++written;
    const int64_t now_ns = monotonic_ns();
    if (now_ns >= next_progress_ns) {
      const auto st = source.stats();
      std::fprintf(stderr, "record: %lld frames, %.1f fps, %llu dropped, %llu outages\r",
                   static_cast<long long>(written), written * 1e9 / (now_ns - start_ns),
                   static_cast<unsigned long long>(st.drops),
                   static_cast<unsigned long long>(st.outages));
      next_progress_ns = now_ns + 1'000'000'000;
      progress_shown = true;
    }
  }
  source.stop();
  if (writer) {
    if (auto r = writer->close(); !r && rc == kExitOk) rc = fail(kExitFailure, r.error().message);
  }
  const auto st = source.stats();
  if (progress_shown) std::fputc('\n', stderr);  // end the \r progress line
  std::fprintf(stderr, "record: %lld frames written to %s; %llu dropped, %llu outages\n",
               static_cast<long long>(written), a.out_dir.c_str(),
               static_cast<unsigned long long>(st.drops),
               static_cast<unsigned long long>(st.outages));
  if (rc == kExitOk && written == 0) rc = fail(kExitFailure, "no frame was captured");
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
  cmd->add_option("--jpeg-quality", args->jpeg_quality,
                  "Write JPEG frames at this quality (1..100) instead of PNG")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--seed", args->seed, "Synthetic scene seed (fixtures, clutter, noise)");
  cmd->add_flag("--realtime", args->realtime_replay,
                "Pace a replay source by its recorded timestamps instead of as fast as possible");
  cmd->callback([args] { set_exit_code(run_record(*args)); });
}

const CommandRegistrar kReg{"record", &add_record_command};

}  // namespace
}  // namespace ceilpose::ctl
