#include "calibration/calibration_files.h"

#include <memory>

#include "calibration/camera_info_file.h"
#include "calibration/map_file.h"

namespace ceilpose {

Result<void> load_calibration_files(const CalibrationFiles& files, const std::string& capture,
                                    PipelineConfig* pipeline) {
  CameraIntrinsics camera = pipeline->intrinsics;
  if (!files.camera_file.empty()) {
    auto read = read_camera_info_file(files.camera_file);
    if (!read) return read.error();
    auto size =
        check_calibration_size(*read, files.camera_file, camera.width, camera.height, capture);
    if (!size) return size;
    const double readout_ms = camera.readout_ms;  // a camera_info has no row timing
    camera = *read;
    camera.readout_ms = readout_ms;
  }
  std::shared_ptr<const CeilingMap> map;
  if (!files.map_file.empty()) {
    auto read = read_map_file(files.map_file, pipeline->layout);
    if (!read) return read.error();
    map = std::make_shared<const CeilingMap>(std::move(*read));
  }
  pipeline->intrinsics = camera;
  pipeline->map = std::move(map);
  return {};
}

}  // namespace ceilpose
