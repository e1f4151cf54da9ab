#include "calibration/mount_fragment.h"

#include <cmath>
#include <cstdio>

#include "core/text_file.h"

namespace ceilpose {
namespace {

std::string key_line(const char* key, double value, double sigma) {
  char line[128];
  std::snprintf(line, sizeof line, "  %-17s %.6f   # +- %.6f\n", key, value, sigma);
  return line;
}

}  // namespace

std::string mount_fragment_text(const MountFragment& f) {
  std::string out;
  size_t from = 0;
  while (from <= f.comment.size() && !f.comment.empty()) {
    const size_t end = f.comment.find('\n', from);
    out += "# " + f.comment.substr(from, end == std::string::npos ? end : end - from) + "\n";
    if (end == std::string::npos) break;
    from = end + 1;
  }
  out += "# Use as --config (or merge into the configuration's mount: section).\nmount:\n";
  const CameraMount& m = f.mount;
  out += key_line("offset_forward_m:", m.offset_forward_m, f.sigma_forward_m);
  out += key_line("offset_left_m:", m.offset_left_m, f.sigma_left_m);
  out += key_line("yaw_rad:", m.yaw_rad, f.sigma_yaw_rad);
  if (f.with_tilt_and_height) {
    out += key_line("tilt_x_rad:", m.tilt_x_rad, f.sigma_tilt_rad[0]);
    out += key_line("tilt_y_rad:", m.tilt_y_rad, f.sigma_tilt_rad[1]);
    char line[160];
    std::snprintf(line, sizeof line,
                  "  lens_height_m:    %.6f   # held (the focal lengths absorb an error in it)\n",
                  m.lens_height_m);
    out += line;
  }
  return out;
}

Result<void> write_mount_fragment(const std::string& path, const MountFragment& f) {
  const CameraMount& m = f.mount;
  for (double v : {m.offset_forward_m, m.offset_left_m, m.yaw_rad, m.tilt_x_rad, m.tilt_y_rad,
                   m.lens_height_m, f.sigma_forward_m, f.sigma_left_m, f.sigma_yaw_rad,
                   f.sigma_tilt_rad[0], f.sigma_tilt_rad[1]})
    if (!std::isfinite(v)) return make_error(path + ": not written: the mount found is not finite");
  return replace_file(path, mount_fragment_text(f));
}

MountFragment fragment_of(const MountEstimate& estimate, const CameraMount& base,
                          std::string comment) {
  MountFragment f;
  f.comment = std::move(comment);
  f.mount = base;
  f.mount.offset_forward_m = estimate.offset_forward_m;
  f.mount.offset_left_m = estimate.offset_left_m;
  f.mount.yaw_rad = estimate.yaw_rad;
  f.sigma_forward_m = estimate.sigma_forward_m;
  f.sigma_left_m = estimate.sigma_left_m;
  f.sigma_yaw_rad = estimate.sigma_yaw_rad;
  return f;
}

}  // namespace ceilpose
