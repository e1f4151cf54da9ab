// The reader never crashes and never passes a damaged frame: every prefix of
// a frame file is rejected, and random damage to any file of a recording
// gives either a clean read or an error naming the damaged file.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <string>

#include "recording/recording_reader.h"
#include "tests/recording/recording_test_support.h"

namespace ceilpose::test {
namespace {

namespace fs = std::filesystem;

// Rejects every cut of frame 1: a sample of cut points through the file and
// every one of the last 40 bytes (where the end marker lives).
void expect_every_prefix_rejected(const RecordingSpec& spec, const std::string& frame_file,
                                  const std::string& kind) {
  TempDir tmp;
  const std::string d = tmp.sub("rec");
  write_recording(d, spec);
  const std::string path = d + "/" + frame_file;
  const std::string whole = read_text_file(path);
  auto reader = RecordingReader::open(d);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  Image img;
  for (size_t cut = 0; cut < whole.size(); cut += (whole.size() - cut > 40 ? 37 : 1)) {
    write_text_file(path, whole.substr(0, cut));
    auto ok = reader->load_frame(1, &img);
    ASSERT_FALSE(ok.ok()) << kind << " cut to " << cut << " of " << whole.size()
                          << " bytes was accepted";
    EXPECT_NE(ok.error().message.find(frame_file + " (frames.csv:3)"), std::string::npos)
        << ok.error().message;
  }
  write_text_file(path, whole);
  EXPECT_TRUE(reader->load_frame(1, &img).ok()) << "the whole file must still load";
}

TEST(RecordingRobustness, EveryPrefixOfAPngFrameIsRejected) {
  RecordingSpec spec;
  spec.frames = 2;
  expect_every_prefix_rejected(spec, "frames/000001.png", "PNG");
}

TEST(RecordingRobustness, EveryPrefixOfAJpegFrameIsRejected) {
  RecordingSpec spec;
  spec.frames = 2;
  spec.jpeg_quality = 90;
  expect_every_prefix_rejected(spec, "frames/000001.jpg", "JPEG");
}

// Flips `flips` random bytes of the file (never the same damage twice: the
// seed differs per round).
void damage(const std::string& path, std::mt19937* rng, int flips) {
  std::string bytes = read_text_file(path);
  if (bytes.empty()) return;
  std::uniform_int_distribution<size_t> at(0, bytes.size() - 1);
  std::uniform_int_distribution<int> value(0, 255);
  for (int k = 0; k < flips; ++k) bytes[at(*rng)] = static_cast<char>(value(*rng));
  write_text_file(path, bytes);
}

TEST(RecordingRobustness, RandomDamageGivesACleanReadOrAnErrorNamingTheFile) {
  const char* targets[] = {"recording.yaml", "frames.csv", "frames/000002.png"};
  std::mt19937 rng(20261122);
  int rejected = 0;
  int rounds = 0;
  for (const char* target : targets) {
    for (int round = 0; round < 40; ++round, ++rounds) {
      TempDir tmp;
      const std::string d = tmp.sub("rec");
      RecordingSpec spec;
      spec.frames = 3;
      write_recording(d, spec);
      damage(d + "/" + target, &rng, 1 + round % 4);
      const std::string error = first_reader_error(d);  // must return, whatever the damage
      if (error.empty()) continue;
      ++rejected;
      // A damaged frames.csv can name a frame file that does not exist.
      const bool names_target =
          error.find(fs::path(target).filename().string()) != std::string::npos;
      const bool names_csv_line = error.find("frames.csv:") != std::string::npos;
      EXPECT_TRUE(names_target || names_csv_line)
          << "damage to " << target << " reported as: " << error;
    }
  }
  // Most random damage must be noticed (PNG CRCs, YAML keys, CSV numbers).
  EXPECT_GT(rejected, rounds / 2) << rejected << " of " << rounds << " damaged recordings rejected";
}

}  // namespace
}  // namespace ceilpose::test
