#include "calibration/camera_info_file.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <vector>

#include "calibration/yaml_fields.h"
#include "core/text_file.h"

namespace ceilpose {
namespace {

using namespace calibration_detail;

// `key`: {rows: R, cols: C, data: [R·C finite numbers]}.
Result<std::vector<double>> matrix(const std::string& path, const YAML::Node& root, const char* key,
                                   int rows, int cols) {
  const YAML::Node m = root[key];
  if (!m.IsDefined() || m.IsNull())
    return make_error(where(path, root) + ": missing key '" + key + "'");
  const std::string shape = std::to_string(rows) + " x " + std::to_string(cols);
  if (!m.IsMap())
    return make_error(where(path, m) + ": key '" + key + "' must be {rows, cols, data}");
  auto r = integer(path, m, "rows", std::string(key) + ".rows");
  if (!r) return r.error();
  auto c = integer(path, m, "cols", std::string(key) + ".cols");
  if (!c) return c.error();
  const YAML::Node data = m["data"];
  if (*r != rows || *c != cols || !data.IsDefined() || !data.IsSequence() ||
      data.size() != static_cast<size_t>(rows * cols)) {
    return make_error(where(path, m) + ": key '" + key + "' must be a " + shape + " matrix with " +
                      std::to_string(rows * cols) + " numbers in data");
  }
  std::vector<double> out(static_cast<size_t>(rows * cols));
  for (size_t k = 0; k < out.size(); ++k) {
    if (!data[k].IsScalar() || !YAML::convert<double>::decode(data[k], out[k]) ||
        !std::isfinite(out[k])) {
      return make_error(where(path, data[k]) + ": " + key + ".data[" + std::to_string(k) +
                        "] must be a finite number");
    }
  }
  return out;
}

// Shortest text that reads back as the same double; always with a decimal
// point, as ROS writes them.
std::string numbers(const double* v, int n) {
  std::string out;
  char buf[40];
  for (int k = 0; k < n; ++k) {
    const auto end = std::to_chars(buf, buf + sizeof buf, v[k]).ptr;
    std::string text(buf, end);
    if (text.find_first_of(".en") == std::string::npos) text += ".0";
    out += (k == 0 ? "" : ", ") + text;
  }
  return out;
}

}  // namespace

Result<CameraIntrinsics> read_camera_info_file(const std::string& path) {
  constexpr size_t kMaxCameraInfoNodes = 1000;  // a camera_info file has about 60
  auto root = load_yaml_mapping(path, "camera calibration (camera_info YAML)", kMaxCameraInfoNodes);
  if (!root) return root.error();
  CameraIntrinsics k;
  for (auto [key, dst] :
       {std::pair{"image_width", &k.width}, std::pair{"image_height", &k.height}}) {
    auto v = integer(path, *root, key, key);
    if (!v) return v.error();
    if (*v <= 0 || *v > 16384)
      return make_error(where(path, (*root)[key]) + ": " + key + " must be in 1..16384");
    *dst = *v;
  }
  auto km = matrix(path, *root, "camera_matrix", 3, 3);
  if (!km) return km.error();
  const std::vector<double>& m = *km;
  if (!(m[0] > 0.0) || !(m[4] > 0.0) || m[1] != 0.0 || m[3] != 0.0 || m[6] != 0.0 || m[7] != 0.0 ||
      m[8] != 1.0) {
    return make_error(where(path, (*root)["camera_matrix"]) +
                      ": camera_matrix must be [fx, 0, cx, 0, fy, cy, 0, 0, 1] with fx, fy > 0");
  }
  k.fx = m[0];
  k.cx = m[2];
  k.fy = m[4];
  k.cy = m[5];
  // A principal point outside the image is no lens (issue 28: every pose
  // came out valid and 11.6 m off).
  if (!(k.cx >= 0.0 && k.cx <= k.width - 1.0 && k.cy >= 0.0 && k.cy <= k.height - 1.0)) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  ": camera_matrix's principal point (%.6g, %.6g) px lies outside the %d x %d "
                  "image",
                  k.cx, k.cy, k.width, k.height);
    return make_error(where(path, (*root)["camera_matrix"]) + msg);
  }
  // Absent, distortion_model is plumb_bob: the five coefficients SPEC §9
  // reads can mean nothing else (docs/decisions.md).
  const YAML::Node model = (*root)["distortion_model"];
  if (model.IsDefined() && !(model.IsScalar() && model.Scalar() == "plumb_bob")) {
    return make_error(where(path, model) + ": distortion_model '" +
                      (model.IsScalar() ? model.Scalar() : std::string("?")) +
                      "' is not supported (ceilpose's camera model is plumb_bob, SPEC §3)");
  }
  auto d = matrix(path, *root, "distortion_coefficients", 1, 5);
  if (!d) return d.error();
  for (size_t c = 0; c < 5; ++c) k.distortion[c] = (*d)[c];
  if (const std::string lens = distortion_problem(k); !lens.empty())
    return make_error(where(path, (*root)["distortion_coefficients"]) +
                      ": distortion_coefficients: " + lens);
  // ROS writes both; ceilpose uses neither, but a file that carries them
  // malformed, or a rectification it would silently ignore, is not a
  // calibration to trust.
  if ((*root)["rectification_matrix"].IsDefined()) {
    auto r = matrix(path, *root, "rectification_matrix", 3, 3);
    if (!r) return r.error();
    for (size_t c = 0; c < 9; ++c) {
      if (std::abs((*r)[c] - (c % 4 == 0 ? 1.0 : 0.0)) > 1e-9) {
        return make_error(where(path, (*root)["rectification_matrix"]) +
                          ": rectification_matrix must be the identity: ceilpose does not "
                          "rectify (a stereo camera's rectified calibration?)");
      }
    }
  }
  if ((*root)["projection_matrix"].IsDefined()) {
    auto pm = matrix(path, *root, "projection_matrix", 3, 4);
    if (!pm) return pm.error();
  }
  return k;
}

std::string camera_info_text(const CameraIntrinsics& k, const std::string& camera_name) {
  const double km[9] = {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0};
  const double r[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  const double p[12] = {k.fx, 0.0, k.cx, 0.0, 0.0, k.fy, k.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  std::string out;
  out += "image_width: " + std::to_string(k.width) + "\n";
  out += "image_height: " + std::to_string(k.height) + "\n";
  out += "camera_name: " + camera_name + "\n";
  out += "camera_matrix: {rows: 3, cols: 3, data: [" + numbers(km, 9) + "]}\n";
  out += "distortion_model: plumb_bob\n";
  out += "distortion_coefficients: {rows: 1, cols: 5, data: [" + numbers(k.distortion.data(), 5) +
         "]}\n";
  out += "rectification_matrix: {rows: 3, cols: 3, data: [" + numbers(r, 9) + "]}\n";
  out += "projection_matrix: {rows: 3, cols: 4, data: [" + numbers(p, 12) + "]}\n";
  return out;
}

Result<void> write_camera_info_file(const std::string& path, const CameraIntrinsics& camera,
                                    const std::string& camera_name, const std::string& comment) {
  bool finite = camera.fx > 0.0 && camera.fy > 0.0 && std::isfinite(camera.fx) &&
                std::isfinite(camera.fy) && std::isfinite(camera.cx) && std::isfinite(camera.cy);
  for (double d : camera.distortion) finite = finite && std::isfinite(d);
  if (!finite)
    return make_error(path + ": not written: the camera found is not finite (fx " +
                      std::to_string(camera.fx) + ", fy " + std::to_string(camera.fy) + ")");
  return replace_file(path, comment + camera_info_text(camera, camera_name));
}

Result<void> check_calibration_size(const CameraIntrinsics& calibration, const std::string& origin,
                                    int capture_width_px, int capture_height_px,
                                    const std::string& capture) {
  if (calibration.width == capture_width_px && calibration.height == capture_height_px) return {};
  return make_error(origin + ": calibrated for " + std::to_string(calibration.width) + "x" +
                    std::to_string(calibration.height) + " px but " + capture + " is " +
                    std::to_string(capture_width_px) + "x" + std::to_string(capture_height_px) +
                    " px (SPEC §9: recalibrate at the capture size; no rescaling)");
}

}  // namespace ceilpose
