// The recording reader (SPEC §4): one input is recording.yaml, frames.csv
// and the bytes of every frame file it names, cut by "\n--8<--\n" lines.
// Opening must give a recording or an error; every frame of an opened one
// decodes or gives an error. Invariants of what it accepts: finite camera
// numbers, timestamps that never go back, finite ground truth; and the
// recording written again by RecordingWriter (camera, rows, the decoded
// frames) reads back with the same pixels, and written once more, the same
// camera and rows.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/image.h"
#include "fuzz/fuzz_support.h"
#include "recording/recording_reader.h"
#include "recording/recording_writer.h"

namespace {

using namespace ceilpose;

constexpr size_t kFramesChecked = 4;
constexpr int64_t kMaxPixelsRewritten = 1'000'000;  // encoding costs; the fuzzer's frames are small

void check(bool ok, const std::string& what) {
  if (!ok) fuzz::invariant_broken("fuzz_recording", what);
}

void check_accepted(const RecordingReader& reader) {
  const CameraIntrinsics& k = reader.camera().intrinsics;
  for (double v : {k.fx, k.fy, k.cx, k.cy, k.readout_ms})
    check(std::isfinite(v), "a non-finite camera number");
  for (double d : k.distortion) check(std::isfinite(d), "a non-finite distortion");
  int64_t last_ns = INT64_MIN;
  for (const RecordingRow& row : reader.rows()) {
    check(row.timestamp_ns >= last_ns, "timestamps go back");
    last_ns = row.timestamp_ns;
    if (row.has_ground_truth)
      check(std::isfinite(row.ground_truth.x_m) && std::isfinite(row.ground_truth.y_m) &&
                std::isfinite(row.ground_truth.yaw_rad),
            "non-finite ground truth");
  }
}

// Writes `frames` (decoded from `reader`'s first rows) as a new recording in
// `dir`; false when the writer refuses (a reason it must give, not a crash).
bool rewrite(const RecordingReader& reader, const std::vector<Image>& frames,
             const std::string& dir) {
  auto writer = RecordingWriter::create(dir, reader.camera());
  if (!writer) return false;
  for (size_t i = 0; i < frames.size(); ++i) {
    const RecordingRow& row = reader.rows()[i];
    if (!writer->append(frames[i].view(), row.timestamp_ns,
                        row.has_ground_truth ? &row.ground_truth : nullptr))
      return false;
  }
  return static_cast<bool>(writer->close());
}

bool same_rows(const RecordingReader& a, const RecordingReader& b) {
  if (a.rows().size() != b.rows().size()) return false;
  for (size_t i = 0; i < a.rows().size(); ++i) {
    const RecordingRow &x = a.rows()[i], &y = b.rows()[i];
    if (x.timestamp_ns != y.timestamp_ns || x.has_ground_truth != y.has_ground_truth ||
        (x.has_ground_truth &&
         (x.ground_truth.x_m != y.ground_truth.x_m || x.ground_truth.y_m != y.ground_truth.y_m ||
          x.ground_truth.yaw_rad != y.ground_truth.yaw_rad)))
      return false;
  }
  return true;
}

bool same_pixels(const Image& a, const Image& b) {
  return a.width() == b.width() && a.height() == b.height() && a.format() == b.format() &&
         std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view parts[3];
  fuzz::split_input(data, size, parts, 3);
  const std::string& dir = fuzz::scratch_dir();
  const std::string in = dir + "/in";
  std::error_code ec;
  std::filesystem::create_directories(in + "/frames", ec);
  fuzz::write_bytes(in + "/recording.yaml", parts[0]);
  fuzz::write_bytes(in + "/frames.csv", parts[1]);
  for (const char* name : {"/frames/000000.png", "/frames/000001.png", "/frames/000000.jpg"})
    fuzz::write_bytes(in + name, parts[2]);
  auto reader = RecordingReader::open(in);
  if (!reader) return 0;
  check_accepted(*reader);

  std::vector<Image> frames;
  for (size_t i = 0; i < reader->rows().size() && i < kFramesChecked; ++i) {
    Image image;
    if (!reader->load_frame(i, &image)) break;
    frames.push_back(std::move(image));
  }
  const CameraIntrinsics& k = reader->camera().intrinsics;
  if (frames.empty() || int64_t{k.width} * k.height > kMaxPixelsRewritten) return 0;
  if (!rewrite(*reader, frames, dir + "/once")) return 0;
  auto once = RecordingReader::open(dir + "/once");
  check(static_cast<bool>(once), "its rewrite is refused: " + (once ? "" : once.error().message));
  for (size_t i = 0; i < frames.size(); ++i) {
    Image again;
    check(static_cast<bool>(once->load_frame(i, &again)), "a rewritten frame does not decode");
    check(same_pixels(frames[i], again), "a rewritten frame has other pixels");
  }
  check(rewrite(*once, frames, dir + "/twice"), "the rewrite cannot be rewritten");
  auto twice = RecordingReader::open(dir + "/twice");
  check(static_cast<bool>(twice), "the second rewrite is refused");
  check(twice->camera().intrinsics == once->camera().intrinsics &&
            twice->camera().source == once->camera().source,
        "written and read, the camera changed");
  check(same_rows(*once, *twice), "written and read, the rows changed");
  return 0;
}
