// `ceilposectl inspect` and `ceilposectl locate --replay` on valid and
// malformed recordings: exit status and what they say on stderr.
#include <gtest/gtest.h>

#include "core/exit_codes.h"
#include "tests/ctl/run_ceilposectl.h"
#include "tests/recording/recording_test_support.h"

namespace ceilpose::test {
namespace {

class InspectCommand : public ::testing::Test {
 protected:
  void SetUp() override { write_recording(dir_, RecordingSpec{}); }
  TempDir tmp_;
  const std::string dir_ = tmp_.sub("rec");
};

TEST_F(InspectCommand, SummarisesAValidRecording) {
  const CommandOutput r = run_ceilposectl({"inspect", dir_});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // 5 frames 16.666667 ms apart: 4 intervals, 0.0667 s, 60 fps.
  expect_mentions(r.out,
                  {"frames        5 (5 PNG, 0 JPEG)", "duration_s    0.067", "fps           60.00",
                   "size          64x48", "ground truth  yes (5 of 5 frames)"});
}

TEST_F(InspectCommand, JsonSummaryHasFramesDurationFpsSizeAndGroundTruth) {
  const CommandOutput r = run_ceilposectl({"inspect", dir_, "--json"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  expect_mentions(r.out, {"\"valid\":true", "\"frames\":5", "\"duration_s\":0.066667",
                          "\"fps\":60.000", "\"size\":\"64x48\"", "\"width\":64", "\"height\":48",
                          "\"has_ground_truth\":true", "\"decoded\":false"});
}

TEST_F(InspectCommand, DecodeReportsProgressOnStderrAndDecodeTime) {
  const CommandOutput r = run_ceilposectl({"inspect", dir_, "--json", "--decode"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  expect_mentions(r.err, {"5/5"});
  expect_mentions(r.out, {"\"decoded\":true", "\"decode_ms_per_frame\":"});
}

TEST_F(InspectCommand, MissingDirectoryArgumentIsAUsageError) {
  const CommandOutput r = run_ceilposectl({"inspect"});
  EXPECT_EQ(r.exit_code, kExitUsage);
}

// Makes the malformed recording of `mc` in a fresh directory under `tmp`.
std::string malformed_recording(const MalformedCase& mc, const TempDir& tmp) {
  const std::string d = tmp.sub("rec");
  write_recording(d, mc.spec);
  mc.corrupt(d);
  return d;
}

class MalformedRecordingCommand : public ::testing::TestWithParam<MalformedCase> {
 protected:
  TempDir tmp_;
};

TEST_P(MalformedRecordingCommand, InspectExitsWithBadInputAndNamesTheDefect) {
  const MalformedCase& mc = GetParam();
  const std::string d = malformed_recording(mc, tmp_);
  std::vector<std::string> args{"inspect", d};
  if (mc.found_by == FoundBy::kDecode) args.push_back("--decode");
  const CommandOutput r = run_ceilposectl(args);
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
  expect_mentions(r.err, mc.expected);
  EXPECT_EQ(r.out, "") << "no summary for a malformed recording";
}

TEST_P(MalformedRecordingCommand, LocateReplayExitsNonZeroAndNamesTheDefect) {
  const MalformedCase& mc = GetParam();
  const std::string d = malformed_recording(mc, tmp_);
  const CommandOutput r = run_ceilposectl({"locate", "--replay", d});
  EXPECT_NE(r.exit_code, 0) << r.err;
  expect_mentions(r.err, mc.expected);
}

INSTANTIATE_TEST_SUITE_P(AllCases, MalformedRecordingCommand,
                         ::testing::ValuesIn(malformed_cases()),
                         [](const ::testing::TestParamInfo<MalformedCase>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace ceilpose::test
