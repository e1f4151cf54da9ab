// The ceiling-map reader (SPEC §8) on arbitrary bytes. A map it accepts has
// finite numbers only, and written and read again is the same text.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "calibration/map_file.h"
#include "core/ceiling_layout.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ceilpose;
  const CeilingLayout layout;
  const std::string path = fuzz::scratch_dir() + "/map.yaml";
  fuzz::write_bytes(path, std::string_view(reinterpret_cast<const char*>(data), size));
  const auto map = read_map_file(path, layout);
  if (!map) return 0;
  const int n = layout.codes();
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const MarkerPlacement* p = map->find(i, j);
      if (p == nullptr) continue;
      for (double v : {p->x_m, p->y_m, p->yaw_rad, p->sigma_m, p->sigma_yaw_rad})
        if (!std::isfinite(v)) fuzz::invariant_broken("fuzz_map", "a non-finite number in a map");
    }
  const std::string text = map_text(*map, layout);
  fuzz::write_bytes(path, text);
  const auto again = read_map_file(path, layout);
  if (!again)
    fuzz::invariant_broken("fuzz_map", "its own text is refused: " + again.error().message);
  if (map_text(*again, layout) != text)
    fuzz::invariant_broken("fuzz_map", "written and read, the map changed");
  return 0;
}
