// ceilposectl inspect: validates a recording (SPEC §4) and summarises it.
#include <unistd.h>

#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <string>

#include "core/image.h"
#include "core/json_text.h"
#include "ctl/command_registry.h"
#include "recording/recording_reader.h"

namespace ceilpose::ctl {
namespace {

struct InspectArgs {
  std::string dir;
  bool json = false;
  bool decode = false;
};

struct Summary {
  size_t frames = 0;
  double duration_s = 0.0;
  double fps = 0.0;  // 0 when fewer than two frames or no time passes
  size_t ground_truth_frames = 0;
  size_t png_frames = 0;
  size_t jpeg_frames = 0;
  bool decoded = false;
  double decode_ms_per_frame = 0.0;      // wall clock
  double decode_cpu_ms_per_frame = 0.0;  // this thread's CPU time: comparable on a loaded machine
};

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Progress goes to stderr: a rewritten line on a terminal, a line per tenth
// otherwise (logs stay short).
class Progress {
 public:
  explicit Progress(size_t total) : total_(total), tty_(::isatty(STDERR_FILENO) == 1) {}
  void update(size_t done) {
    if (total_ == 0) return;
    const size_t tenth = done * 10 / total_;
    if (tty_) {
      std::fprintf(stderr, "\rdecoding %zu/%zu", done, total_);
      if (done == total_) std::fputc('\n', stderr);
    } else if (tenth != last_tenth_ || done == total_) {
      std::fprintf(stderr, "decoded %zu/%zu frames\n", done, total_);
    }
    last_tenth_ = tenth;
  }
  void abandon() {
    if (tty_) std::fputc('\n', stderr);
  }

 private:
  size_t total_;
  bool tty_;
  size_t last_tenth_ = 0;
};

// Checks (or decodes) every frame; on the first defect prints it and returns false.
bool check_frames(const RecordingReader& reader, bool decode, Summary* s) {
  const auto& rows = reader.rows();
  Image image;
  Progress progress(rows.size());
  const auto start = std::chrono::steady_clock::now();
  const double start_cpu_ms = thread_cpu_ms();
  for (size_t i = 0; i < rows.size(); ++i) {
    auto ok = decode ? reader.load_frame(i, &image) : reader.check_frame(i);
    if (!ok) {
      if (decode) progress.abandon();
      std::cerr << "ceilposectl inspect: " << ok.error().message << "\n";
      return false;
    }
    if (decode) progress.update(i + 1);
  }
  if (decode) {
    const double elapsed_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    s->decoded = true;
    const double n = static_cast<double>(rows.size());
    s->decode_ms_per_frame = rows.empty() ? 0.0 : elapsed_ms / n;
    s->decode_cpu_ms_per_frame = rows.empty() ? 0.0 : (thread_cpu_ms() - start_cpu_ms) / n;
  }
  return true;
}

void count_encodings(const RecordingReader& reader, Summary* s) {
  for (const auto& row : reader.rows()) {
    const auto dot = row.file.rfind('.');
    const std::string ext = dot == std::string::npos ? "" : row.file.substr(dot + 1);
    if (ext == "jpg" || ext == "jpeg" || ext == "JPG" || ext == "JPEG") {
      ++s->jpeg_frames;
    } else {
      ++s->png_frames;
    }
  }
}

Summary summarise(const RecordingReader& reader) {
  Summary s;
  const auto& rows = reader.rows();
  s.frames = rows.size();
  if (rows.size() >= 2) {
    const int64_t span_ns = rows.back().timestamp_ns - rows.front().timestamp_ns;
    s.duration_s = static_cast<double>(span_ns) * 1e-9;
    if (span_ns > 0) s.fps = static_cast<double>(rows.size() - 1) / s.duration_s;
  }
  for (const auto& row : rows) s.ground_truth_frames += row.has_ground_truth ? 1 : 0;
  count_encodings(reader, &s);
  return s;
}

// Shortest text that reads back as the same double (camera values are
// printed as recording.yaml holds them).
std::string shortest(double v) {
  std::array<char, 32> buf{};
  const auto end = std::to_chars(buf.data(), buf.data() + buf.size(), v).ptr;
  return std::string(buf.data(), end);
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

void print_json(const RecordingReader& reader, const Summary& s) {
  const CameraIntrinsics& k = reader.camera().intrinsics;
  std::string out = "{\"dir\":" + json_quote(reader.dir()) + ",\"valid\":true";
  auto field = [&out](const char* name, const std::string& value) {
    out += ",\"";
    out += name;
    out += "\":";
    out += value;
  };
  field("frames", std::to_string(s.frames));
  field("duration_s", fixed(s.duration_s, 6));
  field("fps", s.fps > 0.0 ? fixed(s.fps, 3) : "null");
  field("size", "\"" + std::to_string(k.width) + "x" + std::to_string(k.height) + "\"");
  namespace key = camera_keys;
  field(key::kWidth, std::to_string(k.width));
  field(key::kHeight, std::to_string(k.height));
  field(key::kFx, shortest(k.fx));
  field(key::kFy, shortest(k.fy));
  field(key::kCx, shortest(k.cx));
  field(key::kCy, shortest(k.cy));
  std::string distortion = "[";
  for (size_t c = 0; c < k.distortion.size(); ++c) {
    if (c > 0) distortion += ',';
    distortion += shortest(k.distortion[c]);
  }
  field(key::kDistortion, distortion + "]");
  field("has_ground_truth", s.ground_truth_frames > 0 ? "true" : "false");
  field("ground_truth_frames", std::to_string(s.ground_truth_frames));
  field("png_frames", std::to_string(s.png_frames));
  field("jpeg_frames", std::to_string(s.jpeg_frames));
  field("source", json_quote(reader.camera().source));
  field("decoded", s.decoded ? "true" : "false");
  if (s.decoded) {
    field("decode_ms_per_frame", fixed(s.decode_ms_per_frame, 3));
    field("decode_cpu_ms_per_frame", fixed(s.decode_cpu_ms_per_frame, 3));
  }
  out += "}";
  std::cout << out << std::endl;
}

void print_text(const RecordingReader& reader, const Summary& s) {
  const CameraIntrinsics& k = reader.camera().intrinsics;
  std::printf("recording     %s (valid%s)\n", reader.dir().c_str(),
              s.decoded ? ", every frame decoded" : ", frame files checked, not decoded");
  std::printf("frames        %zu (%zu PNG, %zu JPEG)\n", s.frames, s.png_frames, s.jpeg_frames);
  std::printf("duration_s    %.3f\n", s.duration_s);
  if (s.fps > 0.0) {
    std::printf("fps           %.2f\n", s.fps);
  } else {
    std::printf("fps           n/a\n");
  }
  std::printf("size          %dx%d\n", k.width, k.height);
  std::printf("intrinsics    fx %g fy %g cx %g cy %g distortion [%g, %g, %g, %g, %g]\n", k.fx, k.fy,
              k.cx, k.cy, k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3],
              k.distortion[4]);
  std::printf("ground truth  %s (%zu of %zu frames)\n", s.ground_truth_frames > 0 ? "yes" : "no",
              s.ground_truth_frames, s.frames);
  if (!reader.camera().source.empty()) {
    std::printf("source        %s\n", reader.camera().source.c_str());
  }
  if (s.decoded) {
    std::printf("decode_ms     %.3f per frame (%.3f ms CPU)\n", s.decode_ms_per_frame,
                s.decode_cpu_ms_per_frame);
  }
  std::fflush(stdout);
}

void run_inspect(const InspectArgs& args) {
  auto reader = RecordingReader::open(args.dir);
  if (!reader) {
    std::cerr << "ceilposectl inspect: " << reader.error().message << "\n";
    set_exit_code(kExitBadInput);
    return;
  }
  Summary s = summarise(*reader);
  if (!check_frames(*reader, args.decode, &s)) {
    set_exit_code(kExitBadInput);
    return;
  }
  if (args.json) {
    print_json(*reader, s);
  } else {
    print_text(*reader, s);
  }
  set_exit_code(kExitOk);
}

void add_inspect_command(CLI::App& app) {
  auto args = std::make_shared<InspectArgs>();
  CLI::App* cmd = app.add_subcommand(
      "inspect",
      "Validate a recording (SPEC §4) and print a summary: frames, duration, fps, size, ground "
      "truth.\nChecks recording.yaml, every frames.csv row and every frame file's structure "
      "(complete PNG/JPEG, size, 8-bit RGB or grey); with --decode also decodes every frame.\n"
      "Exit 0 when valid, 4 with the defect (file and line) on stderr when malformed.");
  cmd->add_option("dir", args->dir, "Recording directory (holds recording.yaml, frames.csv)")
      ->required();
  cmd->add_flag("--json", args->json, "Print the summary as one JSON object");
  cmd->add_flag("--decode", args->decode,
                "Also decode every frame (progress on stderr) and report the decode time");
  cmd->callback([args] { run_inspect(*args); });
}

const CommandRegistrar kInspectRegistrar{"inspect", &add_inspect_command};

}  // namespace
}  // namespace ceilpose::ctl
