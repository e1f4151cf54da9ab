#pragma once
// The camera calibration file of SPEC §9: ROS camera_info YAML, as ROS's
// camera_calibration writes it and camera_calibration_parsers reads it.
#include <string>

#include "core/camera_model.h"
#include "core/result.h"

namespace ceilpose {

// Reads fx, fy, cx, cy, the image size and plumb_bob coefficients. Rejects,
// naming the file, line and key: malformed YAML, a matrix of the wrong shape,
// a distortion model other than plumb_bob, a non-finite or non-positive
// focal length.
Result<CameraIntrinsics> read_camera_info_file(const std::string& path);

// The intrinsics as camera_info text (identity rectification, projection
// [K | 0]).
std::string camera_info_text(const CameraIntrinsics& camera, const std::string& camera_name);

// Writes the file (atomically), `comment` first (lines starting "# "); a
// camera with a non-finite or non-positive focal length, or a non-finite
// term, is refused and nothing is written.
Result<void> write_camera_info_file(const std::string& path, const CameraIntrinsics& camera,
                                    const std::string& camera_name = "ceilpose",
                                    const std::string& comment = "");

// SPEC §9: a calibration made at another image size is an error, not a
// silent rescale. `origin` names the calibration, `capture` the size it must
// match.
Result<void> check_calibration_size(const CameraIntrinsics& calibration, const std::string& origin,
                                    int capture_width_px, int capture_height_px,
                                    const std::string& capture);

}  // namespace ceilpose
