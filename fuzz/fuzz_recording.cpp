// The recording reader (SPEC §4): one input is recording.yaml, frames.csv
// and the bytes of every frame file it names, cut by "\n--8<--\n" lines.
// Opening must give a recording or an error; every frame of an opened one
// decodes or gives an error.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "core/image.h"
#include "fuzz/fuzz_support.h"
#include "recording/recording_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ceilpose;
  std::string_view parts[3];
  fuzz::split_input(data, size, parts, 3);
  const std::string& dir = fuzz::scratch_dir();
  std::error_code ec;
  std::filesystem::create_directories(dir + "/frames", ec);
  fuzz::write_bytes(dir + "/recording.yaml", parts[0]);
  fuzz::write_bytes(dir + "/frames.csv", parts[1]);
  for (const char* name : {"/frames/000000.png", "/frames/000001.png", "/frames/000000.jpg"})
    fuzz::write_bytes(dir + name, parts[2]);
  auto reader = RecordingReader::open(dir);
  if (!reader) return 0;
  Image image;
  for (size_t i = 0; i < reader->rows().size() && i < 4; ++i) (void)reader->load_frame(i, &image);
  return 0;
}
