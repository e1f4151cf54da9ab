// Frozen recordings (tests/data/golden, committed PNG and JPEG frames) through
// `ceilposectl locate`, against the output committed beside them
// (expected.jsonl, written by locate when the frames were frozen; proc_us
// dropped). The simulator and the pipeline share their conventions, so a
// change to one of them could cancel out in the other; here it shows as a
// failing test and, once accepted, as a diff of expected.jsonl. To refreeze
// after a deliberate change: for d in tests/data/golden/*/; do
// build/release/ctl/ceilposectl locate --replay $d | sed 's/,"proc_us":[0-9]*//'
// > $d/expected.jsonl; done
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "recording/recording_reader.h"

namespace ceilpose {
namespace {

namespace fs = std::filesystem;

const fs::path kGolden = fs::path(CEILPOSE_SOURCE_DIR) / "tests" / "data" / "golden";

// Built before this test (tests/pipeline/CMakeLists.txt depends on it).
fs::path ctl_binary() { return CEILPOSECTL_PATH; }

std::vector<std::string> read_lines(std::istream& in) {
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// The raw text of "key"'s value in a flat JSON object ("" when absent).
std::string raw(const std::string& line, const std::string& key) {
  const size_t at = line.find("\"" + key + "\":");
  if (at == std::string::npos) return "";
  const size_t begin = at + key.size() + 3;
  size_t end = begin;
  if (line[begin] == '[') {
    end = line.find(']', begin) + 1;
  } else {
    while (end < line.size() && line[end] != ',' && line[end] != '}') ++end;
  }
  return line.substr(begin, end - begin);
}

double number(const std::string& line, const std::string& key) {
  return std::strtod(raw(line, key).c_str(), nullptr);
}

class GoldenRecording : public ::testing::TestWithParam<std::string> {};

TEST_P(GoldenRecording, LocateGivesTheFrozenOutput) {
  const fs::path dir = kGolden / GetParam();
  std::ifstream expected_file(dir / "expected.jsonl");
  ASSERT_TRUE(expected_file) << dir / "expected.jsonl";
  const std::vector<std::string> expected = read_lines(expected_file);
  auto reader = RecordingReader::open(dir.string());
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  ASSERT_EQ(expected.size(), reader->rows().size());

  const std::string cmd =
      ctl_binary().string() + " locate --replay " + dir.string() + " 2>&1 </dev/null";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string text;
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;) text.append(buf, n);
  const int status = ::pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << text;
  std::istringstream out(text);
  const std::vector<std::string> got = read_lines(out);
  ASSERT_EQ(got.size(), expected.size()) << text;

  for (size_t k = 0; k < got.size(); ++k) {
    const std::string& g = got[k];
    const std::string& e = expected[k];
    for (const char* key : {"index", "timestamp_ns", "valid", "mode", "markers", "refusal"})
      EXPECT_EQ(raw(g, key), raw(e, key)) << key << " of frame " << k << "\n got " << g;
    if (raw(e, "valid") != "true") continue;
    // 10 µm / 10 µrad: compilers and sanitizers may move the last printed
    // digits; a convention change moves millimetres.
    EXPECT_NEAR(number(g, "x_m"), number(e, "x_m"), 1e-5) << g;
    EXPECT_NEAR(number(g, "y_m"), number(e, "y_m"), 1e-5) << g;
    EXPECT_NEAR(number(g, "yaw_rad"), number(e, "yaw_rad"), 1e-5) << g;
    // And the frozen output itself is right: within 0.5 mm of the truth.
    const RecordingRow& row = reader->rows()[k];
    ASSERT_TRUE(row.has_ground_truth);
    EXPECT_LT(std::hypot(number(e, "x_m") - row.ground_truth.x_m,
                         number(e, "y_m") - row.ground_truth.y_m),
              0.0005)
        << e;
  }
}

INSTANTIATE_TEST_SUITE_P(Frozen, GoldenRecording,
                         ::testing::Values("random_640", "edges_640", "nominal_320"));

}  // namespace
}  // namespace ceilpose
