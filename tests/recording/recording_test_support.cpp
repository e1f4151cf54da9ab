#include "tests/recording/recording_test_support.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "recording/recording_writer.h"

namespace ceilpose::test {

namespace fs = std::filesystem;

TempDir::TempDir() {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") +
                        "/ceilpose-recording-test-XXXXXX";
  if (::mkdtemp(pattern.data()) == nullptr) {
    ADD_FAILURE() << "mkdtemp " << pattern << " failed";
  }
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

Image pattern_image(int width, int height, PixelFormat format, int frame) {
  Image img(width, height, format);
  const int channels = bytes_per_pixel(format);
  for (int y = 0; y < height; ++y) {
    uint8_t* row = img.row(y);
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        row[x * channels + c] = static_cast<uint8_t>(x * 3 + y * 5 + c * 70 + frame * 11);
      }
    }
  }
  return img;
}

RecordingCamera test_camera(int width, int height) {
  RecordingCamera cam;
  cam.intrinsics.width = width;
  cam.intrinsics.height = height;
  cam.intrinsics.fx = 53.0;
  cam.intrinsics.fy = 53.5;
  cam.intrinsics.cx = (width - 1) * 0.5;
  cam.intrinsics.cy = (height - 1) * 0.5;
  cam.intrinsics.distortion = {-0.1, 0.01, 0.001, -0.002, 0.0005};
  cam.intrinsics.readout_ms = 12.5;
  cam.source = "unit test \"pattern\"";
  return cam;
}

void write_recording(const std::string& dir, const RecordingSpec& spec) {
  auto writer = RecordingWriter::create(dir, test_camera(spec.width, spec.height));
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  for (int f = 0; f < spec.frames; ++f) {
    const Image img = pattern_image(spec.width, spec.height, spec.format, f);
    const Pose2D gt{0.3 * f, -0.2 * f, 0.1 * f - 1.0};
    auto ok = writer->append(img.view(), spec.first_timestamp_ns + f * spec.period_ns,
                             spec.ground_truth ? &gt : nullptr, spec.jpeg_quality);
    ASSERT_TRUE(ok.ok()) << ok.error().message;
  }
  auto closed = writer->close();
  ASSERT_TRUE(closed.ok()) << closed.error().message;
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

void replace_line(const std::string& path, int line_no, const std::string& text) {
  std::istringstream in(read_text_file(path));
  std::string line;
  std::string out;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    out += (n == line_no ? text : line) + "\n";
  }
  ASSERT_GE(n, line_no) << path << " has only " << n << " lines";
  write_text_file(path, out);
}

void expect_mentions(const std::string& message, const std::vector<std::string>& words) {
  for (const auto& word : words) {
    EXPECT_NE(message.find(word), std::string::npos) << "expected '" << word << "' in: " << message;
  }
}

void RecordingTest::open_reader() {
  auto r = RecordingReader::open(dir_);
  ASSERT_TRUE(r.ok()) << r.error().message;
  reader_.emplace(std::move(*r));
}

void RecordingTest::load(size_t i) {
  if (!reader_) {
    ASSERT_NO_FATAL_FAILURE(open_reader());
  }
  auto ok = reader_->load_frame(i, &image_);
  ASSERT_TRUE(ok.ok()) << ok.error().message;
}

std::string first_reader_error(const std::string& dir) {
  auto reader = RecordingReader::open(dir);
  if (!reader) return reader.error().message;
  Image img;
  for (size_t i = 0; i < reader->rows().size(); ++i) {
    auto ok = reader->load_frame(i, &img);
    if (!ok) return ok.error().message;
  }
  return "";
}

namespace {

void truncate_file(const std::string& path, double keep_fraction) {
  const auto size = fs::file_size(path);
  fs::resize_file(path, static_cast<uintmax_t>(static_cast<double>(size) * keep_fraction));
}

void write_png(const std::string& path, const cv::Mat& image) {
  ASSERT_TRUE(cv::imwrite(path, image)) << path;
}

// frames.csv line of frame f (header is line 1), as the writer writes it with
// ground truth.
std::string row_text(int f, int64_t timestamp_ns) {
  return std::to_string(f) + "," + std::to_string(timestamp_ns) + ",frames/00000" +
         std::to_string(f) + ".png,0.5,0.5,0";
}

constexpr int64_t kT0 = 1'000'000'000;
constexpr int64_t kDt = 16'666'667;

std::vector<MalformedCase> make_cases() {
  const RecordingSpec png;  // 5 RGB PNG frames with ground truth, 64x48
  RecordingSpec jpeg;
  jpeg.jpeg_quality = 90;
  std::vector<MalformedCase> c;
  auto yaml = [](const std::string& dir) { return dir + "/recording.yaml"; };
  auto csv = [](const std::string& dir) { return dir + "/frames.csv"; };
  // Lines of the writer's recording.yaml: 1 format, 2 version, 3 camera:,
  // 4 width, 5 height, 6 fx, 7 fy, 8 cx, 9 cy, 10 distortion, 11 readout_ms,
  // 12 source.
  c.push_back({"MissingRecordingYaml",
               png,
               [=](const std::string& d) { fs::remove(yaml(d)); },
               {"recording.yaml", "missing"}});
  c.push_back({"YamlSyntaxError",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 5, "  height: 48: 3"); },
               {"recording.yaml:5:", "YAML syntax error"}});
  c.push_back({"YamlNotAMapping",
               png,
               [=](const std::string& d) { write_text_file(yaml(d), "- just\n- a list\n"); },
               {"recording.yaml:1", "mapping"}});
  c.push_back({"WrongFormat",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 1, "format: other-recording"); },
               {"recording.yaml:1", "format 'other-recording'"}});
  c.push_back({"UnknownVersion",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 2, "version: 2"); },
               {"recording.yaml:2", "unsupported version 2"}});
  c.push_back({"MissingCameraKey",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 6, ""); },
               {"recording.yaml:4", "missing key 'camera.fx'"}});
  c.push_back({"NonNumericCameraWidth",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 4, "  width: wide"); },
               {"recording.yaml:4", "'camera.width'"}});
  c.push_back({"NegativeFocalLength",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 7, "  fy: -530"); },
               {"recording.yaml:7", "'camera.fy'", "positive"}});
  c.push_back({"DuplicateCameraKey",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 7, "  fx: 600"); },
               {"recording.yaml:7", "key 'camera.fx' appears twice"}});
  c.push_back(
      {"DistortionNoLensCanHave",
       png,
       [=](const std::string& d) {
         replace_line(yaml(d), 10, "  distortion: [1e300, 0, 0, 0, 0]");
       },
       {"recording.yaml:10", "camera.distortion: the distortion cannot be inverted at pixel"}});
  c.push_back({"DistortionWithTwoCoefficients",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 10, "  distortion: [0.1, 0]"); },
               {"recording.yaml:10", "distortion"}});
  c.push_back({"NegativeReadout",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 11, "  readout_ms: -3"); },
               {"recording.yaml:11", "'camera.readout_ms'", "0 to 1000 ms"}});
  // Issue 15: 100000x100000 aborted the daemon on bad_alloc.
  c.push_back({"HugeWidth",
               png,
               [=](const std::string& d) { replace_line(yaml(d), 4, "  width: 100000"); },
               {"recording.yaml:4", "'camera.width' must be 1 to 8192 pixels, got 100000"}});
  c.push_back({"TooManyPixels",
               png,
               [=](const std::string& d) {
                 replace_line(yaml(d), 4, "  width: 8000");
                 replace_line(yaml(d), 5, "  height: 8000");
               },
               {"recording.yaml:5", "must be at most 33554432 pixels, got 8000x8000"}});
  c.push_back({"RecordingYamlIsADirectory",
               png,
               [=](const std::string& d) {
                 fs::remove(yaml(d));
                 fs::create_directory(yaml(d));
               },
               {"recording.yaml", "it is a directory"}});
  c.push_back(
      {"FramePathClimbsOut",
       png,
       [=](const std::string& d) { replace_line(csv(d), 2, "0,1000000000,../outside.png,0,0,0"); },
       {"frames.csv:2", "'../outside.png' must stay inside the recording directory"}});
  c.push_back({"MissingFramesCsv",
               png,
               [=](const std::string& d) { fs::remove(csv(d)); },
               {"frames.csv", "missing"}});
  c.push_back({"HeaderOnlyNoFrames",
               png,
               [=](const std::string& d) {
                 write_text_file(csv(d), "index,timestamp_ns,file,gt_x_m,gt_y_m,gt_yaw_rad\n");
               },
               {"frames.csv:1", "no frames, only the header"}});
  c.push_back({"NulByteInAFileName",
               png,
               [=](const std::string& d) {
                 const char row[] = "0,1000000000,frames/000000.png\0.txt,0.5,0.5,0";
                 replace_line(csv(d), 2, std::string(row, sizeof row - 1));
               },
               {"frames.csv:2", "a NUL byte at character 31"}});
  c.push_back({"EmptyFramesCsv",
               png,
               [=](const std::string& d) { write_text_file(csv(d), ""); },
               {"frames.csv:1", "empty"}});
  c.push_back({"HeaderWithoutTimestampColumn",
               png,
               [=](const std::string& d) {
                 replace_line(csv(d), 1, "index,time_ns,file,gt_x_m,gt_y_m,gt_yaw_rad");
               },
               {"frames.csv:1", "timestamp_ns"}});
  c.push_back({"HeaderWithPartialGroundTruth",
               png,
               [=](const std::string& d) {
                 replace_line(csv(d), 1, "index,timestamp_ns,file,gt_x_m,gt_y_m,note");
               },
               {"frames.csv:1", "gt_yaw_rad"}});
  c.push_back({"RowWithTooFewFields",
               png,
               [=](const std::string& d) {
                 replace_line(csv(d), 4,
                              "2," + std::to_string(kT0 + 2 * kDt) + ",frames/000002.png");
               },
               {"frames.csv:4", "3 fields", "header has 6"}});
  c.push_back({"RowWithNonNumericTimestamp",
               png,
               [=](const std::string& d) {
                 replace_line(csv(d), 4, "2,12abc,frames/000002.png,0.5,0.5,0");
               },
               {"frames.csv:4", "timestamp_ns '12abc'"}});
  c.push_back({"RowWithNonNumericGroundTruth",
               png,
               [=](const std::string& d) {
                 replace_line(csv(d), 3,
                              "1," + std::to_string(kT0 + kDt) + ",frames/000001.png,0.5,north,0");
               },
               {"frames.csv:3", "gt_y_m 'north'"}});
  c.push_back({"IndexNotFromZero",
               png,
               [=](const std::string& d) {
                 replace_line(csv(d), 2, "1," + std::to_string(kT0) + ",frames/000000.png,0,0,0");
               },
               {"frames.csv:2", "index 1", "expected 0"}});
  c.push_back({"IndexSkipsOne",
               png,
               [=](const std::string& d) { replace_line(csv(d), 4, row_text(3, kT0 + 2 * kDt)); },
               {"frames.csv:4", "index 3", "expected 2"}});
  c.push_back({"TimestampGoesBackwards",
               png,
               [=](const std::string& d) { replace_line(csv(d), 5, row_text(3, 900)); },
               {"frames.csv:5: timestamp_ns 900 goes backwards (previous " +
                std::to_string(kT0 + 2 * kDt) + ")"}});
  c.push_back({"MissingFrameFile",
               png,
               [=](const std::string& d) { fs::remove(d + "/frames/000002.png"); },
               {"frames/000002.png' (frames.csv:4)", "missing"}});
  c.push_back({"TruncatedPng",
               png,
               [=](const std::string& d) { truncate_file(d + "/frames/000003.png", 0.5); },
               {"frames/000003.png (frames.csv:5)", "truncated PNG"},
               FoundBy::kCheckFrame});
  c.push_back({"PngCutBeforeIend",
               png,
               [=](const std::string& d) {
                 const std::string f = d + "/frames/000003.png";
                 fs::resize_file(f, fs::file_size(f) - 12);  // IEND is the last 12 bytes
               },
               {"frames/000003.png (frames.csv:5)", "truncated PNG", "IEND"},
               FoundBy::kCheckFrame});
  c.push_back({"WrongImageSize",
               png,
               [=](const std::string& d) {
                 write_png(d + "/frames/000001.png", cv::Mat(24, 32, CV_8UC3, cv::Scalar(1, 2, 3)));
               },
               {"frames/000001.png (frames.csv:3)", "32x24", "64x48"},
               FoundBy::kCheckFrame});
  c.push_back({"NonImageFile",
               png,
               [=](const std::string& d) {
                 write_text_file(d + "/frames/000001.png", "this is not a picture\n");
               },
               {"frames/000001.png (frames.csv:3)", "not an image"},
               FoundBy::kCheckFrame});
  c.push_back({"EmptyFrameFile",
               png,
               [=](const std::string& d) { write_text_file(d + "/frames/000004.png", ""); },
               {"frames/000004.png (frames.csv:6)", "empty"},
               FoundBy::kCheckFrame});
  c.push_back({"SixteenBitPng",
               png,
               [=](const std::string& d) {
                 write_png(d + "/frames/000002.png",
                           cv::Mat(48, 64, CV_16UC3, cv::Scalar(9, 9, 9)));
               },
               {"frames/000002.png (frames.csv:4)", "unsupported bit depth 16"},
               FoundBy::kCheckFrame});
  c.push_back({"RgbaPng",
               png,
               [=](const std::string& d) {
                 write_png(d + "/frames/000002.png",
                           cv::Mat(48, 64, CV_8UC4, cv::Scalar(9, 9, 9, 255)));
               },
               {"frames/000002.png (frames.csv:4)", "RGBA"},
               FoundBy::kCheckFrame});
  c.push_back({"TruncatedJpeg",
               jpeg,
               [=](const std::string& d) { truncate_file(d + "/frames/000003.jpg", 0.6); },
               {"frames/000003.jpg (frames.csv:5)", "truncated JPEG"},
               FoundBy::kCheckFrame});
  MalformedCase corrupt{"CorruptPngData",
                        png,
                        [=](const std::string& d) {
                          // Structure intact, compressed bytes (and so the CRC) wrong.
                          const std::string f = d + "/frames/000002.png";
                          std::string bytes = read_text_file(f);
                          const size_t idat = bytes.find("IDAT");
                          for (size_t k = idat + 20; k < idat + 60 && k < bytes.size() - 16; ++k) {
                            bytes[k] = static_cast<char>(bytes[k] ^ 0x5a);
                          }
                          write_text_file(f, bytes);
                        },
                        {"frames/000002.png (frames.csv:4)", "corrupt PNG"}};
  corrupt.found_by = FoundBy::kDecode;
  c.push_back(corrupt);
  return c;
}

}  // namespace

const std::vector<MalformedCase>& malformed_cases() {
  static const std::vector<MalformedCase> cases = make_cases();
  return cases;
}

std::vector<MalformedCase> malformed_frame_cases() {
  std::vector<MalformedCase> out;
  for (const auto& c : malformed_cases()) {
    if (c.found_by != FoundBy::kOpen) out.push_back(c);
  }
  return out;
}

void PrintTo(const MalformedCase& c, std::ostream* os) { *os << c.name; }

}  // namespace ceilpose::test
