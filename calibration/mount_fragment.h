#pragma once
// The configuration fragment that `calibrate mount` and `calibrate robot`
// write (SPEC §10): the mount: keys with their 1-sigma as comments, usable
// as --config or merged into a configuration's mount: section.
#include <array>
#include <string>

#include "calibration/mount_estimate.h"
#include "core/camera_model.h"
#include "core/result.h"

namespace ceilpose {

struct MountFragment {
  std::string comment;  // first lines, each written after "# "
  CameraMount mount;
  double sigma_forward_m = 0.0, sigma_left_m = 0.0, sigma_yaw_rad = 0.0;
  // `calibrate robot` also measures the tilt and states the lens height it
  // held; `calibrate mount` leaves both to the configuration.
  bool with_tilt_and_height = false;
  std::array<double, 2> sigma_tilt_rad{};
};

std::string mount_fragment_text(const MountFragment& fragment);

// Writes it (atomically); a non-finite value is refused and nothing written.
Result<void> write_mount_fragment(const std::string& path, const MountFragment& fragment);

// `base` (the configuration's mount: lens height, tilt) with the estimate's
// offset, yaw and sigmas.
MountFragment fragment_of(const MountEstimate& estimate, const CameraMount& base,
                          std::string comment);

}  // namespace ceilpose
