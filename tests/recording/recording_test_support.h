#pragma once
// Shared by tests/recording and tests/ctl: temporary recordings, written by
// the writer or by hand, and the catalogue of malformed recordings with the
// words their error message must contain.
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "core/image.h"
#include "recording/recording_reader.h"

namespace ceilpose::test {

// A fresh directory under $TMPDIR (or /tmp), removed with its contents on
// destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string sub(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// A deterministic test pattern (gradients plus a per-frame offset) so that
// frames differ from each other and every channel differs from the others.
Image pattern_image(int width, int height, PixelFormat format, int frame);

struct RecordingSpec {
  int frames = 5;
  int width = 64;
  int height = 48;
  PixelFormat format = PixelFormat::kRgb24;
  bool ground_truth = true;
  int jpeg_quality = 0;
  int64_t first_timestamp_ns = 1'000'000'000;
  int64_t period_ns = 16'666'667;
};

RecordingCamera test_camera(int width, int height);

// Writes a valid recording with RecordingWriter; fails the current test
// (ADD_FAILURE) when the writer reports an error.
void write_recording(const std::string& dir, const RecordingSpec& spec);

std::string read_text_file(const std::string& path);
void write_text_file(const std::string& path, const std::string& text);
// Replaces line `line_no` (1-based) of a text file.
void replace_line(const std::string& path, int line_no, const std::string& text);

// Expects every word in `message` (each failure names the missing word).
void expect_mentions(const std::string& message, const std::vector<std::string>& words);

// Opens the recording and decodes every frame; returns the first error
// message, or "" when the recording is valid.
std::string first_reader_error(const std::string& dir);

// Which reader call must report a defect: open() (YAML, CSV, missing
// files), check_frame() (a frame file's structure) or only load_frame()
// (compressed data corrupt inside an intact container).
enum class FoundBy { kOpen, kCheckFrame, kDecode };

// One malformed recording: made from a valid 5-frame recording at `dir` by
// `corrupt`; every entry of `expected` must appear in the error message.
struct MalformedCase {
  std::string name;
  RecordingSpec spec;
  std::function<void(const std::string& dir)> corrupt;
  std::vector<std::string> expected;
  FoundBy found_by = FoundBy::kOpen;
};

const std::vector<MalformedCase>& malformed_cases();
// The cases whose defect is in a frame file (found by check_frame or decoding).
std::vector<MalformedCase> malformed_frame_cases();

// A test with a temporary recording directory `dir_` (not yet created) and
// the reader opened on it by open_reader().
class RecordingTest : public ::testing::Test {
 protected:
  // Opens dir_ into reader_; fails the test (fatally) when open() fails.
  void open_reader();
  // Opens dir_ and decodes frame i into image_; fails the test when either fails.
  void load(size_t i);

  TempDir tmp_;
  const std::string dir_ = tmp_.sub("rec");
  std::optional<RecordingReader> reader_;
  Image image_;
};

// googletest prints a parameter with this instead of its bytes.
void PrintTo(const MalformedCase& c, std::ostream* os);

}  // namespace ceilpose::test
