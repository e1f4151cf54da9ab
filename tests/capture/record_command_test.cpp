// `ceilposectl record`, run as a process: what it writes reads back as a valid
// SPEC §4 recording, and its exit codes follow the documented ones.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "recording/recording_reader.h"

namespace ceilpose {
namespace {

namespace fs = std::filesystem;

class RecordCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() /
            ("ceilpose_record_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base_);
    fs::create_directories(base_);
  }
  void TearDown() override { fs::remove_all(base_); }

  // Runs ceilposectl with `args`; returns its exit status, stderr in *err.
  int run(const std::string& args, std::string* err) {
    const fs::path err_file = base_ / "stderr.txt";
    const std::string cmd =
        std::string(CEILPOSECTL_PATH) + " " + args + " >/dev/null 2>" + err_file.string();
    const int status = std::system(cmd.c_str());
    std::ifstream in(err_file);
    std::stringstream ss;
    ss << in.rdbuf();
    *err = ss.str();
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  fs::path base_;
};

TEST_F(RecordCommandTest, RecordsSyntheticFramesWithGroundTruth) {
  const fs::path out = base_ / "synthetic";
  std::string err;
  ASSERT_EQ(run("record --source synthetic --out " + out.string() + " --frames 4", &err), 0) << err;
  auto reader = RecordingReader::open(out.string());
  ASSERT_TRUE(reader) << reader.error().message;
  ASSERT_EQ(reader->rows().size(), 4u);
  EXPECT_TRUE(reader->has_ground_truth_columns());
  EXPECT_EQ(reader->camera().intrinsics.width, 640);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_TRUE(reader->rows()[i].has_ground_truth);
    if (i > 0) {
      EXPECT_GT(reader->rows()[i].timestamp_ns, reader->rows()[i - 1].timestamp_ns);
    }
    Image img;
    auto loaded = reader->load_frame(i, &img);
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_EQ(img.width(), 640);
  }
}

TEST_F(RecordCommandTest, ReRecordingAReplayKeepsTimestampsAndGroundTruth) {
  const fs::path first = base_ / "first";
  const fs::path second = base_ / "second";
  std::string err;
  ASSERT_EQ(run("record --source synthetic --out " + first.string() + " --frames 3", &err), 0)
      << err;
  ASSERT_EQ(run("record --source replay:" + first.string() + " --out " + second.string(), &err), 0)
      << err;
  auto a = RecordingReader::open(first.string());
  auto b = RecordingReader::open(second.string());
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->rows().size(), b->rows().size());
  for (size_t i = 0; i < a->rows().size(); ++i) {
    EXPECT_EQ(a->rows()[i].timestamp_ns, b->rows()[i].timestamp_ns);
    EXPECT_DOUBLE_EQ(a->rows()[i].ground_truth.x_m, b->rows()[i].ground_truth.x_m);
    EXPECT_DOUBLE_EQ(a->rows()[i].ground_truth.yaw_rad, b->rows()[i].ground_truth.yaw_rad);
  }
}

TEST_F(RecordCommandTest, ALiveSourceWithoutAFrameOrTimeLimitIsAUsageError) {
  std::string err;
  EXPECT_EQ(run("record --source synthetic --out " + (base_ / "x").string(), &err), 2);
  EXPECT_NE(err.find("--frames"), std::string::npos) << err;
}

TEST_F(RecordCommandTest, AMissingCameraExitsOneNamingTheDevice) {
  std::string err;
  EXPECT_EQ(run("record --source v4l2:/dev/ceilpose-no-such-video --out " + (base_ / "x").string() +
                    " --frames 1",
                &err),
            1);
  EXPECT_NE(err.find("/dev/ceilpose-no-such-video"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(base_ / "x")) << "no recording is created without a frame";
}

TEST_F(RecordCommandTest, AMalformedReplayExitsFour) {
  const fs::path bad = base_ / "bad";
  fs::create_directories(bad);
  std::ofstream(bad / "recording.yaml") << "format: not-a-recording\n";
  std::string err;
  EXPECT_EQ(
      run("record --source replay:" + bad.string() + " --out " + (base_ / "x").string(), &err), 4);
  EXPECT_NE(err.find("recording.yaml"), std::string::npos) << err;
}

}  // namespace
}  // namespace ceilpose
