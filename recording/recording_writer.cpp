#include "recording/recording_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <vector>

#include "codec/jpeg_codec.h"
#include "codec/png_codec.h"
#include "core/text_file.h"
#include "core/unique_fd.h"
#include "recording/frame_file.h"
#include "recording/recording_format.h"

namespace ceilpose {

namespace fmt = recording_format;

namespace {

// Shortest text that reads back to the same double, so rows round-trip exactly.
std::string number_text(double v) {
  std::array<char, 32> buf{};
  const auto [p, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  (void)ec;  // 32 chars always hold a double's shortest form
  return std::string(buf.data(), p);
}

std::string yaml_quoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\x%02x",
                    static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += esc;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string yaml_text(const RecordingCamera& camera) {
  const CameraIntrinsics& k = camera.intrinsics;
  std::string y;
  y += std::string("format: ") + fmt::kFormat + "\n";
  y += "version: " + std::to_string(fmt::kVersion) + "\n";
  y += "camera:\n";
  namespace key = camera_keys;
  y += std::string("  ") + key::kWidth + ": " + std::to_string(k.width) + "\n";
  y += std::string("  ") + key::kHeight + ": " + std::to_string(k.height) + "\n";
  y += std::string("  ") + key::kFx + ": " + number_text(k.fx) + "\n";
  y += std::string("  ") + key::kFy + ": " + number_text(k.fy) + "\n";
  y += std::string("  ") + key::kCx + ": " + number_text(k.cx) + "\n";
  y += std::string("  ") + key::kCy + ": " + number_text(k.cy) + "\n";
  y += std::string("  ") + key::kDistortion + ": [";
  for (size_t c = 0; c < k.distortion.size(); ++c) {
    if (c > 0) y += ", ";
    y += number_text(k.distortion[c]);
  }
  y += "]   # k1 k2 p1 p2 k3\n";
  y += std::string("  ") + key::kReadoutMs + ": " + number_text(k.readout_ms) +
       "   # rolling-shutter readout, 0 = global\n";
  if (!camera.source.empty()) y += "source: " + yaml_quoted(camera.source) + "\n";
  return y;
}

}  // namespace

struct RecordingWriter::State {
  std::string dir;
  RecordingCamera camera;
  UniqueFd csv;
  off_t csv_bytes = 0;  // what frames.csv holds of whole lines
  size_t frames = 0;
  int64_t last_timestamp_ns = 0;
  bool ground_truth_columns = false;
  bool closed = false;
  std::vector<uint8_t> encoded;  // reused encoder output
  codec::JpegCodec jpeg;
  std::string path;  // reused frame file path
};

RecordingWriter::RecordingWriter() : s_(std::make_unique<State>()) {}
RecordingWriter::RecordingWriter(RecordingWriter&&) noexcept = default;
RecordingWriter& RecordingWriter::operator=(RecordingWriter&&) noexcept = default;
RecordingWriter::~RecordingWriter() = default;

size_t RecordingWriter::frames_written() const { return s_ ? s_->frames : 0; }

Result<RecordingWriter> RecordingWriter::create(const std::string& dir,
                                                const RecordingCamera& camera) {
  namespace fs = std::filesystem;
  const CameraIntrinsics& k = camera.intrinsics;
  if (k.width <= 0 || k.height <= 0 || !(k.fx > 0.0) || !(k.fy > 0.0) || !std::isfinite(k.fx) ||
      !std::isfinite(k.fy) || !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    return make_error(dir + ": invalid camera for a recording (size " + std::to_string(k.width) +
                      "x" + std::to_string(k.height) + ", fx/fy must be positive and finite)");
  }
  for (const double d : k.distortion) {
    if (!std::isfinite(d)) return make_error(dir + ": camera distortion must be finite");
  }
  std::error_code ec;
  const fs::path root(dir);
  if (fs::exists(root, ec)) {
    if (!fs::is_directory(root, ec)) return make_error(dir + ": exists and is not a directory");
    if (!fs::is_empty(root, ec)) {
      return make_error(dir + ": directory is not empty; refusing to write a recording into it");
    }
  }
  fs::create_directories(root / fmt::kFramesDir, ec);
  if (ec)
    return make_error(dir + ": cannot create " + fmt::kFramesDir + "/ (" + ec.message() + ")");

  RecordingWriter w;
  w.s_->dir = dir;
  w.s_->camera = camera;
  const std::string yaml = yaml_text(camera);
  auto wrote = write_file(dir + "/" + fmt::kYamlName, yaml.data(), yaml.size());
  if (!wrote) return wrote.error();
  const std::string csv_path = dir + "/" + fmt::kCsvName;
  w.s_->csv = UniqueFd(::open(csv_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (!w.s_->csv.valid())
    return make_error(csv_path + ": cannot create (" + std::strerror(errno) + ")");
  return w;
}

// On a full disk what is on disk must stay a valid recording of the frames
// written so far: each line goes out whole in unbuffered writes, and a line
// cut short is cut off again, back to the last whole one.
Result<void> RecordingWriter::append_lines(const char* data, size_t size) {
  State& s = *s_;
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(s.csv.get(), data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = n < 0 ? errno : ENOSPC;
      const bool rolled_back = ::ftruncate(s.csv.get(), s.csv_bytes) == 0 &&
                               ::lseek(s.csv.get(), s.csv_bytes, SEEK_SET) == s.csv_bytes;
      return make_error(s.dir + "/" + fmt::kCsvName + ": write error (" + std::strerror(e) +
                        "); the recording keeps its first " + std::to_string(s.frames) + " frames" +
                        (rolled_back ? "" : " (the cut line could not be removed)"));
    }
    done += static_cast<size_t>(n);
  }
  s.csv_bytes += static_cast<off_t>(size);
  return {};
}

Result<void> RecordingWriter::append(const ImageView& frame, int64_t timestamp_ns,
                                     const Pose2D* ground_truth, int jpeg_quality) {
  if (!s_ || s_->closed) return make_error("recording writer: append() after close()");
  State& s = *s_;
  // Built only for an error: the success path allocates nothing of its own.
  const auto frame_name = [&s] { return "frame " + std::to_string(s.frames) + " of " + s.dir; };
  if (frame.data == nullptr) return make_error(frame_name() + ": empty image");
  const CameraIntrinsics& k = s.camera.intrinsics;
  if (frame.width != k.width || frame.height != k.height) {
    return make_error(frame_name() + ": image is " + std::to_string(frame.width) + "x" +
                      std::to_string(frame.height) + ", the recording's camera is " +
                      std::to_string(k.width) + "x" + std::to_string(k.height));
  }
  if (s.frames > 0 && timestamp_ns < s.last_timestamp_ns) {
    return make_error(frame_name() + ": timestamp_ns " + std::to_string(timestamp_ns) +
                      " goes backwards (previous " + std::to_string(s.last_timestamp_ns) + ")");
  }
  // The first frame fixes the header; later frames must agree with it.
  const bool gt_columns = s.frames == 0 ? ground_truth != nullptr : s.ground_truth_columns;
  if ((ground_truth != nullptr) != gt_columns) {
    return make_error(frame_name() + (gt_columns
                                          ? ": no ground truth, but the first frame had it"
                                          : ": has ground truth, but the first frame had none"));
  }
  if (ground_truth != nullptr &&
      !(std::isfinite(ground_truth->x_m) && std::isfinite(ground_truth->y_m) &&
        std::isfinite(ground_truth->yaw_rad))) {
    return make_error(frame_name() + ": ground truth is not finite");
  }
  if (jpeg_quality < 0 || jpeg_quality > 100) {
    return make_error(frame_name() + ": jpeg_quality " + std::to_string(jpeg_quality) +
                      " outside 0..100 (0 writes PNG)");
  }

  const uint8_t* bytes = nullptr;
  size_t size = 0;
  bool jpeg = jpeg_quality > 0;
  if (frame.format == PixelFormat::kMjpeg) {
    // Stored as the camera delivered it; checked so the recording stays readable.
    auto info = inspect_frame_bytes(frame.data, frame.size_bytes);
    if (!info || info->encoding != FrameEncoding::kJpeg) {
      return make_error(frame_name() + ": MJPEG payload is not a complete JPEG" +
                        (info ? std::string() : " (" + info.error().message + ")"));
    }
    if (info->width != k.width || info->height != k.height) {
      return make_error(frame_name() + ": MJPEG payload is " + std::to_string(info->width) + "x" +
                        std::to_string(info->height) + ", the recording's camera is " +
                        std::to_string(k.width) + "x" + std::to_string(k.height));
    }
    bytes = frame.data;
    size = frame.size_bytes;
    jpeg = true;
  } else {
    if (frame.format != PixelFormat::kGray8 && frame.format != PixelFormat::kRgb24 &&
        frame.format != PixelFormat::kBgr24) {
      return make_error(frame_name() + ": cannot store pixel format " + to_string(frame.format) +
                        " (RGB24, BGR24, GREY or MJPEG)");
    }
    // PNG at zlib's fastest level: a live recorder must keep up with the camera.
    const auto encoded = jpeg ? s.jpeg.encode(frame, jpeg_quality, &s.encoded)
                              : codec::encode_png(frame, 1, &s.encoded);
    if (!encoded) return make_error(frame_name() + ": " + encoded.error().message);
    bytes = s.encoded.data();
    size = s.encoded.size();
  }

  char name[32];
  std::snprintf(name, sizeof name, "%s/%06zu.%s", fmt::kFramesDir, s.frames, jpeg ? "jpg" : "png");
  s.path.assign(s.dir);
  s.path += '/';
  s.path += name;
  auto wrote = write_file(s.path, bytes, size);
  if (!wrote) {
    ::unlink(s.path.c_str());  // a frame file cut short is no frame
    return make_error(wrote.error().message + "; the recording keeps its first " +
                      std::to_string(s.frames) + " frames");
  }

  // [header] index,timestamp_ns,file[,gt_x_m,gt_y_m,gt_yaw_rad]: at most 3 x
  // 20 digits, the name and 3 x 24 characters of shortest round-trip doubles.
  std::array<char, 256> row{};
  char* p = row.data();
  if (s.frames == 0) {
    s.ground_truth_columns = gt_columns;
    const std::string_view header = gt_columns ? fmt::kHeaderWithTruth : fmt::kHeader;
    p = std::copy(header.begin(), header.end(), p);
  }
  char* const end = row.data() + row.size() - 1;
  p = std::to_chars(p, end, s.frames).ptr;
  *p++ = ',';
  p = std::to_chars(p, end, timestamp_ns).ptr;
  *p++ = ',';
  for (const char* c = name; *c != '\0'; ++c) *p++ = *c;
  if (ground_truth != nullptr) {
    for (const double v : {ground_truth->x_m, ground_truth->y_m, ground_truth->yaw_rad}) {
      *p++ = ',';
      p = std::to_chars(p, end, v).ptr;
    }
  }
  *p++ = '\n';
  if (auto ok = append_lines(row.data(), static_cast<size_t>(p - row.data())); !ok) {
    ::unlink(s.path.c_str());
    return ok;
  }
  s.last_timestamp_ns = timestamp_ns;
  ++s.frames;
  return {};
}

Result<void> RecordingWriter::close() {
  if (!s_ || s_->closed) return {};
  State& s = *s_;
  s.closed = true;
  const std::string csv_path = s.dir + "/" + fmt::kCsvName;
  if (s.frames == 0 && s.csv_bytes == 0) {
    if (auto ok = append_lines(fmt::kHeader.data(), fmt::kHeader.size()); !ok) return ok;
  }
  // On disk before the command says it is done: frames.csv, and with
  // syncfs the frame files and directory entries too (one call, not one
  // fsync per frame).
  if (::fsync(s.csv.get()) != 0)
    return make_error(csv_path + ": cannot flush to disk (" + std::strerror(errno) + ")");
  if (::syncfs(s.csv.get()) != 0)
    return make_error(s.dir + ": cannot flush to disk (" + std::strerror(errno) + ")");
  if (::close(s.csv.release()) != 0)
    return make_error(csv_path + ": close error (" + std::strerror(errno) + ")");
  return {};
}

}  // namespace ceilpose
