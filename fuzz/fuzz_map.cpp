// The ceiling-map reader (SPEC §8) on arbitrary bytes.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "calibration/map_file.h"
#include "core/ceiling_layout.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ceilpose;
  const std::string path = fuzz::scratch_dir() + "/map.yaml";
  fuzz::write_bytes(path, std::string_view(reinterpret_cast<const char*>(data), size));
  (void)read_map_file(path, CeilingLayout{});
  return 0;
}
