// Writer of SPEC §4 and the round trip through the reader.
#include "recording/recording_writer.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>

#include "recording/recording_format.h"
#include "recording/recording_reader.h"
#include "tests/recording/recording_test_support.h"

namespace ceilpose::test {
namespace {

namespace fs = std::filesystem;

// Pixels of `expected` (as written, in `written_format`) against what the
// reader hands out (RGB24 or GRAY8).
void expect_same_pixels(const Image& expected, PixelFormat written_format, const Image& got) {
  const bool grey = written_format == PixelFormat::kGray8;
  ASSERT_EQ(got.format(), grey ? PixelFormat::kGray8 : PixelFormat::kRgb24);
  ASSERT_EQ(got.width(), expected.width());
  ASSERT_EQ(got.height(), expected.height());
  const int n = grey ? 1 : 3;
  for (int y = 0; y < got.height(); ++y) {
    const uint8_t* e = expected.data() + static_cast<size_t>(y) * expected.stride_bytes();
    const uint8_t* g = got.data() + static_cast<size_t>(y) * got.stride_bytes();
    for (int x = 0; x < got.width(); ++x) {
      for (int c = 0; c < n; ++c) {
        // BGR input is stored as the colour it means, so read back as RGB.
        const int ec = written_format == PixelFormat::kBgr24 ? 2 - c : c;
        ASSERT_EQ(g[x * n + c], e[x * n + ec]) << "pixel (" << x << ", " << y << ") channel " << c;
      }
    }
  }
}

struct RoundTrip {
  const char* name;
  PixelFormat format;
  bool ground_truth;
};

void PrintTo(const RoundTrip& p, std::ostream* os) { *os << p.name; }

class LosslessRoundTrip : public ::testing::TestWithParam<RoundTrip> {};

TEST_P(LosslessRoundTrip, ReadsBackIdenticalPixelsAndRows) {
  const RoundTrip& p = GetParam();
  TempDir tmp;
  const std::string d = tmp.sub("rec");
  RecordingSpec spec;
  spec.format = p.format;
  spec.ground_truth = p.ground_truth;
  spec.frames = 4;
  write_recording(d, spec);

  auto reader = RecordingReader::open(d);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const RecordingCamera expected_cam = test_camera(spec.width, spec.height);
  const CameraIntrinsics& k = reader->camera().intrinsics;
  EXPECT_EQ(k.width, spec.width);
  EXPECT_EQ(k.height, spec.height);
  EXPECT_EQ(k.fx, expected_cam.intrinsics.fx);
  EXPECT_EQ(k.fy, expected_cam.intrinsics.fy);
  EXPECT_EQ(k.cx, expected_cam.intrinsics.cx);
  EXPECT_EQ(k.cy, expected_cam.intrinsics.cy);
  EXPECT_EQ(k.distortion, expected_cam.intrinsics.distortion);
  EXPECT_EQ(k.readout_ms, 12.5);
  EXPECT_EQ(reader->camera().source, expected_cam.source);
  EXPECT_EQ(reader->has_ground_truth_columns(), p.ground_truth);
  ASSERT_EQ(reader->rows().size(), 4u);
  Image got;
  for (int f = 0; f < 4; ++f) {
    const RecordingRow& row = reader->rows()[static_cast<size_t>(f)];
    EXPECT_EQ(row.index, f);
    EXPECT_EQ(row.timestamp_ns, spec.first_timestamp_ns + f * spec.period_ns);
    EXPECT_EQ(row.csv_line, f + 2);
    EXPECT_EQ(row.file, "frames/00000" + std::to_string(f) + ".png");
    EXPECT_EQ(row.has_ground_truth, p.ground_truth);
    if (p.ground_truth) {
      // Exact: the writer prints the shortest text that reads back the same double.
      EXPECT_EQ(row.ground_truth.x_m, 0.3 * f);
      EXPECT_EQ(row.ground_truth.y_m, -0.2 * f);
      EXPECT_EQ(row.ground_truth.yaw_rad, 0.1 * f - 1.0);
    }
    auto ok = reader->load_frame(static_cast<size_t>(f), &got);
    ASSERT_TRUE(ok.ok()) << ok.error().message;
    expect_same_pixels(pattern_image(spec.width, spec.height, p.format, f), p.format, got);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Formats, LosslessRoundTrip,
    ::testing::Values(RoundTrip{"RgbWithGroundTruth", PixelFormat::kRgb24, true},
                      RoundTrip{"RgbWithoutGroundTruth", PixelFormat::kRgb24, false},
                      RoundTrip{"GreyWithGroundTruth", PixelFormat::kGray8, true},
                      RoundTrip{"GreyWithoutGroundTruth", PixelFormat::kGray8, false},
                      RoundTrip{"BgrInputWithGroundTruth", PixelFormat::kBgr24, true}),
    [](const ::testing::TestParamInfo<RoundTrip>& info) { return std::string(info.param.name); });

// A writer on a fresh 64x48 recording at dir_.
class RecordingWriterTest : public RecordingTest {
 protected:
  void SetUp() override {
    auto w = RecordingWriter::create(dir_, test_camera(64, 48));
    ASSERT_TRUE(w.ok()) << w.error().message;
    writer_.emplace(std::move(*w));
  }
  // Appends and returns the error message, "" on success.
  std::string append(const ImageView& view, int64_t timestamp_ns, const Pose2D* gt = nullptr,
                     int jpeg_quality = 0) {
    auto ok = writer_->append(view, timestamp_ns, gt, jpeg_quality);
    return ok.ok() ? "" : ok.error().message;
  }
  std::string append_pattern(int64_t timestamp_ns, const Pose2D* gt = nullptr) {
    const Image img = pattern_image(64, 48, PixelFormat::kRgb24, 0);
    return append(img.view(), timestamp_ns, gt);
  }
  static ImageView mjpeg_view(const std::vector<uint8_t>& jpeg, size_t size_bytes) {
    ImageView view;
    view.data = jpeg.data();
    view.width = 64;
    view.height = 48;
    view.format = PixelFormat::kMjpeg;
    view.size_bytes = size_bytes;
    return view;
  }
  static std::vector<uint8_t> jpeg_64x48() {
    std::vector<uint8_t> jpeg;
    cv::imencode(".jpg", cv::Mat(48, 64, CV_8UC3, cv::Scalar(30, 60, 90)), jpeg);
    return jpeg;
  }

  std::optional<RecordingWriter> writer_;
};

TEST_F(RecordingWriterTest, JpegFramesReadBackCloseToTheOriginal) {
  const Image original = pattern_image(64, 48, PixelFormat::kRgb24, 1);
  ASSERT_EQ(append(original.view(), 1, nullptr, 95), "");
  ASSERT_TRUE(writer_->close().ok());
  ASSERT_NO_FATAL_FAILURE(load(0));
  EXPECT_EQ(reader_->rows()[0].file, "frames/000000.jpg");
  ASSERT_EQ(image_.format(), PixelFormat::kRgb24);
  double sum_abs = 0.0;
  for (size_t i = 0; i < image_.size_bytes(); ++i) {
    sum_abs += std::abs(int{image_.data()[i]} - int{original.data()[i]});
  }
  // Lossy (the pattern has sharp wrap-around edges), but the channel order
  // must survive: with R and B swapped the mean error would be about 100.
  EXPECT_LT(sum_abs / static_cast<double>(image_.size_bytes()), 15.0);
}

TEST_F(RecordingWriterTest, GreyJpegFramesReadBackAsGrey) {
  const Image original = pattern_image(64, 48, PixelFormat::kGray8, 2);
  ASSERT_EQ(append(original.view(), 1, nullptr, 95), "");
  ASSERT_TRUE(writer_->close().ok());
  ASSERT_NO_FATAL_FAILURE(load(0));
  ASSERT_EQ(image_.format(), PixelFormat::kGray8);
  ASSERT_EQ(image_.size_bytes(), original.size_bytes());
  double sum_abs = 0.0;
  for (size_t i = 0; i < image_.size_bytes(); ++i) {
    sum_abs += std::abs(int{image_.data()[i]} - int{original.data()[i]});
  }
  EXPECT_LT(sum_abs / static_cast<double>(image_.size_bytes()), 15.0);
}

TEST_F(RecordingWriterTest, MjpegPayloadIsStoredVerbatim) {
  const std::vector<uint8_t> jpeg = jpeg_64x48();
  ASSERT_EQ(append(mjpeg_view(jpeg, jpeg.size()), 5), "");
  ASSERT_TRUE(writer_->close().ok());
  EXPECT_EQ(read_text_file(dir_ + "/frames/000000.jpg"), std::string(jpeg.begin(), jpeg.end()));
  EXPECT_EQ(first_reader_error(dir_), "");
}

TEST_F(RecordingWriterTest, RefusesATruncatedMjpegPayload) {
  const std::vector<uint8_t> jpeg = jpeg_64x48();
  expect_mentions(append(mjpeg_view(jpeg, jpeg.size() / 2), 5), {"truncated JPEG"});
}

TEST_F(RecordingWriterTest, RefusesANonEmptyDirectory) {
  ASSERT_TRUE(writer_->close().ok());
  auto again = RecordingWriter::create(dir_, test_camera(64, 48));
  ASSERT_FALSE(again.ok());
  expect_mentions(again.error().message, {dir_, "not empty"});
}

TEST(RecordingWriter, UsesAnExistingEmptyDirectory) {
  TempDir tmp;
  auto writer = RecordingWriter::create(tmp.path(), test_camera(64, 48));
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  ASSERT_TRUE(writer->close().ok());
  // Closed before a frame: every reader gives one answer (docs/decisions.md).
  auto reader = RecordingReader::open(tmp.path());
  ASSERT_FALSE(reader.ok());
  expect_mentions(reader.error().message, {"frames.csv:1", "no frames, only the header"});
}

// Issue 15: a full disk used to leave frames.csv cut mid-row with "76
// frames written" reported. A file-size limit stands in for the full disk
// (writes past it fail with EFBIG, after a partial write).
TEST_F(RecordingWriterTest, AFullDiskLeavesAValidRecordingOfTheFramesWritten) {
  const Pose2D gt{1.0, 2.0, 0.5};
  ASSERT_EQ(append_pattern(1000, &gt), "");
  const auto frame_bytes = std::filesystem::file_size(dir_ + "/frames/000000.png");
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  const rlimit small{static_cast<rlim_t>(frame_bytes + 100), old.rlim_max};
  auto* const old_handler = std::signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string error;
  for (int64_t k = 1; k < 100000 && error.empty(); ++k) error = append_pattern(1000 + k, &gt);
  setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  const size_t kept = writer_->frames_written();
  ASSERT_GE(kept, 2u);
  expect_mentions(error,
                  {"frames.csv: write error (File too large); the recording keeps its first " +
                   std::to_string(kept) + " frames"});
  ASSERT_TRUE(writer_->close().ok());
  auto reader = RecordingReader::open(dir_);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  EXPECT_EQ(reader->rows().size(), kept);
  EXPECT_TRUE(reader->has_ground_truth_columns());
}

TEST_F(RecordingWriterTest, RefusesDecreasingTimestamps) {
  ASSERT_EQ(append_pattern(1000), "");
  expect_mentions(append_pattern(900), {"timestamp_ns 900 goes backwards (previous 1000)"});
  EXPECT_EQ(writer_->frames_written(), 1u);
}

TEST_F(RecordingWriterTest, RefusesAFrameOfTheWrongSize) {
  const Image img = pattern_image(32, 48, PixelFormat::kRgb24, 0);
  expect_mentions(append(img.view(), 1000), {"32x48", "64x48"});
}

TEST_F(RecordingWriterTest, RefusesGroundTruthThatComesAndGoes) {
  const Pose2D gt{1.0, 2.0, 0.5};
  ASSERT_EQ(append_pattern(1000, &gt), "");
  expect_mentions(append_pattern(2000), {"no ground truth"});
}

TEST_F(RecordingWriterTest, RefusesUnsupportedPixelFormat) {
  const Image img(64, 48, PixelFormat::kYuyv);
  expect_mentions(append(img.view(), 1000), {"YUYV"});
}

TEST_F(RecordingWriterTest, RefusesAppendAfterClose) {
  ASSERT_TRUE(writer_->close().ok());
  expect_mentions(append_pattern(1000), {"after close"});
}

TEST_F(RecordingWriterTest, WritesStridedViews) {
  // A 64x48 window of a wider image: rows are 80 pixels apart.
  const Image wide = pattern_image(80, 48, PixelFormat::kRgb24, 0);
  ImageView view = wide.view();
  view.width = 64;
  ASSERT_EQ(append(view, 1), "");
  ASSERT_TRUE(writer_->close().ok());
  ASSERT_NO_FATAL_FAILURE(load(0));
  for (int y = 0; y < 48; ++y) {
    ASSERT_EQ(std::memcmp(image_.data() + y * image_.stride_bytes(),
                          wide.data() + y * wide.stride_bytes(), 64 * 3),
              0)
        << "row " << y;
  }
}

// SPEC §4's column names are written once (recording_format.h); the header
// lines the writer writes are made of them, in order.
TEST(RecordingFormat, TheHeaderLinesAreTheColumnNames) {
  namespace f = recording_format;
  const std::string required =
      std::string(f::kColIndex) + "," + f::kColTimestamp + "," + f::kColFile;
  EXPECT_EQ(f::kHeader, required + "\n");
  EXPECT_EQ(f::kHeaderWithTruth,
            required + "," + f::kColGtX + "," + f::kColGtY + "," + f::kColGtYaw + "\n");
}

}  // namespace
}  // namespace ceilpose::test
