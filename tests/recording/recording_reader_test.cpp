// Reader of SPEC §4: reads what the writer and what a hand-made recording
// hold, and rejects each malformed recording naming the file and line.
#include "recording/recording_reader.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/recording/recording_test_support.h"

namespace ceilpose::test {
namespace {

namespace fs = std::filesystem;

class RecordingReaderTest : public RecordingTest {
 protected:
  // A valid recording of `frames` RGB frames with ground truth.
  void write_valid(int frames = 5) {
    RecordingSpec spec;
    spec.frames = frames;
    write_recording(dir_, spec);
  }
  void expect_rgb_at_origin(uint8_t r, uint8_t g, uint8_t b) {
    ASSERT_EQ(image_.format(), PixelFormat::kRgb24);
    EXPECT_EQ(image_.data()[0], r);
    EXPECT_EQ(image_.data()[1], g);
    EXPECT_EQ(image_.data()[2], b);
  }
};

TEST_F(RecordingReaderTest, ReadsHandWrittenRecordingInSpecFormat) {
  fs::create_directories(dir_ + "/frames");
  write_text_file(dir_ + "/recording.yaml",
                  "format: ceilpose-recording\n"
                  "version: 1\n"
                  "camera:\n"
                  "  width: 640\n"
                  "  height: 480\n"
                  "  fx: 530.0\n"
                  "  fy: 530.0\n"
                  "  cx: 319.5\n"
                  "  cy: 239.5\n"
                  "  distortion: [0.0, 0.0, 0.0, 0.0, 0.0]   # k1 k2 p1 p2 k3\n"
                  "source: \"free text: synthetic, v4l2 device, ...\"   # optional\n");
  write_text_file(dir_ + "/frames.csv",
                  "index,timestamp_ns,file,gt_x_m,gt_y_m,gt_yaw_rad\n"
                  "0,1000000000,frames/000000.png,0.9144,1.2192,0.5236\n");
  const cv::Mat bgr(480, 640, CV_8UC3, cv::Scalar(10, 20, 30));  // B, G, R
  ASSERT_TRUE(cv::imwrite(dir_ + "/frames/000000.png", bgr));

  ASSERT_NO_FATAL_FAILURE(load(0));
  const CameraIntrinsics& k = reader_->camera().intrinsics;
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  EXPECT_DOUBLE_EQ(k.fx, 530.0);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
  EXPECT_EQ(k.readout_ms, 0.0) << "absent: a global shutter";
  EXPECT_EQ(reader_->camera().source, "free text: synthetic, v4l2 device, ...");
  ASSERT_EQ(reader_->rows().size(), 1u);
  const RecordingRow& row = reader_->rows()[0];
  EXPECT_EQ(row.index, 0);
  EXPECT_EQ(row.timestamp_ns, 1'000'000'000);
  EXPECT_EQ(row.file, "frames/000000.png");
  EXPECT_TRUE(row.has_ground_truth);
  EXPECT_DOUBLE_EQ(row.ground_truth.x_m, 0.9144);
  EXPECT_DOUBLE_EQ(row.ground_truth.y_m, 1.2192);
  EXPECT_DOUBLE_EQ(row.ground_truth.yaw_rad, 0.5236);
  EXPECT_EQ(row.csv_line, 2);
  expect_rgb_at_origin(30, 20, 10);  // OpenCV's BGR comes out as RGB
}

TEST_F(RecordingReaderTest, IgnoresExtraColumnsAnywhereInTheHeader) {
  write_valid();
  ASSERT_NO_FATAL_FAILURE(open_reader());
  const std::vector<RecordingRow> before = reader_->rows();
  std::string csv = "exposure_us,gt_yaw_rad,file,note,timestamp_ns,gt_x_m,index,gt_y_m\n";
  for (const auto& r : before) {
    csv += "500," + std::to_string(r.ground_truth.yaw_rad) + "," + r.file + ",x," +
           std::to_string(r.timestamp_ns) + "," + std::to_string(r.ground_truth.x_m) + "," +
           std::to_string(r.index) + "," + std::to_string(r.ground_truth.y_m) + "\n";
  }
  write_text_file(dir_ + "/frames.csv", csv);

  ASSERT_NO_FATAL_FAILURE(open_reader());
  ASSERT_EQ(reader_->rows().size(), before.size());
  for (size_t i = 0; i < before.size(); ++i) {
    const auto& a = reader_->rows()[i];
    EXPECT_EQ(a.index, before[i].index);
    EXPECT_EQ(a.timestamp_ns, before[i].timestamp_ns);
    EXPECT_EQ(a.file, before[i].file);
    EXPECT_TRUE(a.has_ground_truth);
    EXPECT_NEAR(a.ground_truth.x_m, before[i].ground_truth.x_m, 1e-6);
    EXPECT_NEAR(a.ground_truth.y_m, before[i].ground_truth.y_m, 1e-6);
    EXPECT_NEAR(a.ground_truth.yaw_rad, before[i].ground_truth.yaw_rad, 1e-6);
  }
}

TEST_F(RecordingReaderTest, AcceptsCrLfLineEndingsAndQuotedFields) {
  write_valid(2);
  write_text_file(dir_ + "/frames.csv",
                  "index,timestamp_ns,\"file\"\r\n"
                  "0,10,\"frames/000000.png\"\r\n"
                  "1,20,frames/000001.png\r\n");
  ASSERT_NO_FATAL_FAILURE(open_reader());
  ASSERT_EQ(reader_->rows().size(), 2u);
  EXPECT_EQ(reader_->rows()[0].file, "frames/000000.png");
  EXPECT_EQ(reader_->rows()[1].timestamp_ns, 20);
  EXPECT_FALSE(reader_->has_ground_truth_columns());
}

TEST_F(RecordingReaderTest, AcceptsAUtf8ByteOrderMarkBeforeTheHeader) {
  write_valid(2);
  write_text_file(dir_ + "/frames.csv", "\xEF\xBB\xBF" + read_text_file(dir_ + "/frames.csv"));
  ASSERT_NO_FATAL_FAILURE(open_reader());
  EXPECT_EQ(reader_->rows().size(), 2u);
}

TEST_F(RecordingReaderTest, RowWithAllGroundTruthFieldsEmptyHasNoGroundTruth) {
  write_valid(2);
  replace_line(dir_ + "/frames.csv", 3, "1,2000000000,frames/000001.png,,,");
  ASSERT_NO_FATAL_FAILURE(open_reader());
  EXPECT_TRUE(reader_->rows()[0].has_ground_truth);
  EXPECT_FALSE(reader_->rows()[1].has_ground_truth);
}

TEST_F(RecordingReaderTest, EqualTimestampsAreAccepted) {
  RecordingSpec spec;
  spec.frames = 3;
  spec.period_ns = 0;
  write_recording(dir_, spec);
  EXPECT_EQ(first_reader_error(dir_), "");
}

TEST_F(RecordingReaderTest, TrailingBlankLinesAreAccepted) {
  write_valid();
  write_text_file(dir_ + "/frames.csv", read_text_file(dir_ + "/frames.csv") + "\n\n");
  ASSERT_NO_FATAL_FAILURE(open_reader());
  EXPECT_EQ(reader_->rows().size(), 5u);
}

TEST_F(RecordingReaderTest, BlankLineBetweenRowsIsRejectedWithItsLine) {
  write_valid();
  replace_line(dir_ + "/frames.csv", 3, "");
  expect_mentions(first_reader_error(dir_), {"frames.csv:3", "empty line"});
}

TEST_F(RecordingReaderTest, MissingDirectoryIsNamed) {
  expect_mentions(first_reader_error(dir_), {dir_, "does not exist"});
}

TEST_F(RecordingReaderTest, AbsoluteFramePathIsRejected) {
  write_valid();
  replace_line(dir_ + "/frames.csv", 2, "0,1000000000," + dir_ + "/frames/000000.png,0,0,0");
  expect_mentions(first_reader_error(dir_), {"frames.csv:2", "relative"});
}

// OpenCV cannot write palette PNGs, so one is made by hand: OpenCV's grey
// PNG with IHDR's colour type set to 3 and a one-colour PLTE chunk, every
// pixel index 0.
std::vector<uint8_t> palette_png(int width, int height, uint8_t r, uint8_t g, uint8_t b) {
  std::vector<uint8_t> png;
  cv::imencode(".png", cv::Mat(height, width, CV_8UC1, cv::Scalar(0)), png);
  auto crc32 = [](const uint8_t* p, size_t n) {
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; ++i) {
      c ^= p[i];
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return c ^ 0xffffffffu;
  };
  auto put32 = [](uint8_t* p, uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = static_cast<uint8_t>(v >> (24 - 8 * k));
  };
  png[25] = 3;                           // IHDR colour type
  put32(&png[29], crc32(&png[12], 17));  // IHDR CRC over type and data
  std::vector<uint8_t> plte = {0, 0, 0, 3, 'P', 'L', 'T', 'E', r, g, b, 0, 0, 0, 0};
  put32(&plte[11], crc32(&plte[4], 7));
  png.insert(png.begin() + 33, plte.begin(), plte.end());  // right after IHDR
  return png;
}

TEST_F(RecordingReaderTest, PalettePngDecodesToRgb) {
  write_valid(1);
  const std::vector<uint8_t> png = palette_png(64, 48, 200, 30, 40);
  write_text_file(dir_ + "/frames/000000.png", std::string(png.begin(), png.end()));
  ASSERT_NO_FATAL_FAILURE(load(0));
  expect_rgb_at_origin(200, 30, 40);
}

TEST_F(RecordingReaderTest, LoadFrameKeepsTheOutputBufferAcrossFrames) {
  write_valid();
  ASSERT_NO_FATAL_FAILURE(load(0));
  const uint8_t* buffer = image_.data();
  for (size_t i = 1; i < reader_->rows().size(); ++i) {
    ASSERT_NO_FATAL_FAILURE(load(i));
    EXPECT_EQ(image_.data(), buffer) << "frame " << i;
  }
}

TEST_F(RecordingReaderTest, FrameIndexOutOfRangeIsAnError) {
  write_valid();
  ASSERT_NO_FATAL_FAILURE(open_reader());
  auto ok = reader_->load_frame(5, &image_);
  ASSERT_FALSE(ok.ok());
  expect_mentions(ok.error().message, {"out of range"});
}

// Issue 28 #21: a 1 MB file name in frames.csv is named in one line of
// message, its start and end with how much was left out, not echoed whole.
TEST_F(RecordingReaderTest, AHugeFileNameIsCutInTheMessage) {
  write_valid(2);
  replace_line(dir_ + "/frames.csv", 2,
               "0,1000000000," + std::string(1'000'000, 'x') + ".png,0.5,0.5,0");
  const std::string error = first_reader_error(dir_);
  ASSERT_FALSE(error.empty());
  EXPECT_LT(error.size(), 600u) << error.substr(0, 600);
  expect_mentions(error, {"frames.csv:2", "more bytes)", "x.png'"});
}

// ---- every malformed recording: an error naming the file and the line ----

class MalformedRecording : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(MalformedRecording, IsRejectedNamingFileAndLine) {
  const MalformedCase& mc = GetParam();
  TempDir tmp;
  const std::string d = tmp.sub("rec");
  write_recording(d, mc.spec);
  ASSERT_EQ(first_reader_error(d), "") << "the recording must be valid before corruption";
  mc.corrupt(d);
  auto reader = RecordingReader::open(d);
  ASSERT_EQ(reader.ok(), mc.found_by != FoundBy::kOpen)
      << (reader.ok() ? "open() accepted it" : reader.error().message);
  const std::string error = first_reader_error(d);
  ASSERT_FALSE(error.empty()) << mc.name << ": the malformed recording was accepted";
  expect_mentions(error, mc.expected);
}

INSTANTIATE_TEST_SUITE_P(AllCases, MalformedRecording, ::testing::ValuesIn(malformed_cases()),
                         [](const ::testing::TestParamInfo<MalformedCase>& info) {
                           return info.param.name;
                         });

// check_frame() finds a damaged frame container without decoding, and
// passes one whose damage only decoding can see.
class MalformedFrame : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(MalformedFrame, CheckFrameReportsExactlyTheStructuralDefects) {
  const MalformedCase& mc = GetParam();
  TempDir tmp;
  const std::string d = tmp.sub("rec");
  write_recording(d, mc.spec);
  mc.corrupt(d);
  auto reader = RecordingReader::open(d);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  std::string error;
  for (size_t i = 0; i < reader->rows().size() && error.empty(); ++i) {
    auto ok = reader->check_frame(i);
    if (!ok) error = ok.error().message;
  }
  if (mc.found_by == FoundBy::kDecode) {
    EXPECT_EQ(error, "") << "structure is intact, only decoding can see the damage";
    return;
  }
  ASSERT_FALSE(error.empty()) << mc.name << ": check_frame accepted every frame";
  expect_mentions(error, mc.expected);
}

INSTANTIATE_TEST_SUITE_P(FrameCases, MalformedFrame, ::testing::ValuesIn(malformed_frame_cases()),
                         [](const ::testing::TestParamInfo<MalformedCase>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace ceilpose::test
