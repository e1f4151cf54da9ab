// The camera_info reader (SPEC §9) on arbitrary bytes. A camera it accepts
// has finite numbers, and written and read again is the same text.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "calibration/camera_info_file.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ceilpose;
  const std::string path = fuzz::scratch_dir() + "/camera.yaml";
  fuzz::write_bytes(path, std::string_view(reinterpret_cast<const char*>(data), size));
  const auto camera = read_camera_info_file(path);
  if (!camera) return 0;
  for (double v : {camera->fx, camera->fy, camera->cx, camera->cy})
    if (!std::isfinite(v)) fuzz::invariant_broken("fuzz_camera_info", "a non-finite intrinsic");
  for (double d : camera->distortion)
    if (!std::isfinite(d)) fuzz::invariant_broken("fuzz_camera_info", "a non-finite distortion");
  const std::string text = camera_info_text(*camera, "fuzz");
  fuzz::write_bytes(path, text);
  const auto again = read_camera_info_file(path);
  if (!again)
    fuzz::invariant_broken("fuzz_camera_info", "its own text is refused: " + again.error().message);
  if (camera_info_text(*again, "fuzz") != text)
    fuzz::invariant_broken("fuzz_camera_info", "written and read, the camera changed");
  return 0;
}
