#include "independent_renderer_support.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

// Everything below is read off SPEC.md, not off core/ or sim/:
//  §1  marker (i, j) centre at (i g, j g, H), x East, y North, z Up;
//  §2  red e in [0, 5 in], green e in [-5 in, 0], n in [-6 in, 6 in]; dots on
//      the rectangles' N-S centre lines at n = +4, 0, -4 in, MSB North; red
//      dots 2 x 1 in, green dots 3 x 2 in (E-W x N-S, full axes); rails 1 in
//      wide along x = i g and y = j g, under the markers;
//  §3  camera axes Xc = (-sin yaw, cos yaw, 0), Yc = (-cos yaw, -sin yaw, 0),
//      Zc = (0, 0, 1) for the camera's own yaw; OpenCV pinhole + plumb_bob;
//      pixel (0, 0) is the centre of the top-left pixel.
namespace ceilpose::testing::xcheck {
namespace {

constexpr double kIn_m = 0.0254;
constexpr double kGrid_m = 0.6096;
constexpr int kCodes = 8;
// Far enough around the camera to cover the widest (distorted) view used:
// the widest lens sees about 1.4 lens-to-ceiling distances off axis.
constexpr double kMinDrawRadius_m = 3.0;
constexpr double kDrawRadiusPerDistance = 1.45;
// Edge subdivision so that distortion bends the drawn outlines.
constexpr double kEdgeStep_m = 0.005;
constexpr int kFixedPointShift = 4;

const cv::Scalar kRed(200, 30, 40);
const cv::Scalar kGreen(40, 160, 70);
const cv::Scalar kDot(25, 25, 25);
const cv::Scalar kTile(215, 215, 205);
const cv::Scalar kRail(170, 170, 170);

class Projector {
 public:
  Projector(const XCamera& camera, const XMount& mount, const XPose& robot) {
    const double c = std::cos(robot.yaw_rad), s = std::sin(robot.yaw_rad);
    const double centre_x_m = robot.x_m + c * mount.offset_forward_m - s * mount.offset_left_m;
    const double centre_y_m = robot.y_m + s * mount.offset_forward_m + c * mount.offset_left_m;
    const double cam_yaw_rad = robot.yaw_rad + mount.yaw_rad;
    const double cc = std::cos(cam_yaw_rad), cs = std::sin(cam_yaw_rad);
    // Rows of the level camera's R_cw are its axes expressed in the world
    // (SPEC §3); a tilted camera turns them about its own Xc by tilt_x, then
    // about the turned Yc by tilt_y: R_wc = L·Rx·Ry, so R_cw = Ryᵀ·Rxᵀ·Lᵀ.
    const cv::Matx33d level_cw(-cs, cc, 0.0,   //
                               -cc, -cs, 0.0,  //
                               0.0, 0.0, 1.0);
    const double ca = std::cos(mount.tilt_x_rad), sa = std::sin(mount.tilt_x_rad);
    const double cb = std::cos(mount.tilt_y_rad), sb = std::sin(mount.tilt_y_rad);
    const cv::Matx33d rx(1.0, 0.0, 0.0, 0.0, ca, -sa, 0.0, sa, ca);
    const cv::Matx33d ry(cb, 0.0, sb, 0.0, 1.0, 0.0, -sb, 0.0, cb);
    const cv::Matx33d r_cw = ry.t() * rx.t() * level_cw;
    const cv::Vec3d centre_w(centre_x_m, centre_y_m, mount.lens_height_m);
    cv::Rodrigues(cv::Mat(r_cw), rvec_);
    tvec_ = cv::Mat(-(r_cw * centre_w));
    k_ = (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
    dist_ = cv::Mat(camera.distortion, true).reshape(1, 1);
    centre_x_m_ = centre_x_m;
    centre_y_m_ = centre_y_m;
    ceiling_m_ = mount.ceiling_height_m;
    draw_radius_m_ = std::max(
        kMinDrawRadius_m, kDrawRadiusPerDistance * (mount.ceiling_height_m - mount.lens_height_m));
  }

  std::vector<cv::Point2d> project(const std::vector<cv::Point3d>& world) const {
    std::vector<cv::Point2d> image;
    cv::projectPoints(world, rvec_, tvec_, k_, dist_, image);
    return image;
  }

  double centre_x_m() const { return centre_x_m_; }
  double centre_y_m() const { return centre_y_m_; }
  double ceiling_m() const { return ceiling_m_; }
  double draw_radius_m() const { return draw_radius_m_; }

 private:
  cv::Mat rvec_, tvec_, k_, dist_;
  double centre_x_m_ = 0.0, centre_y_m_ = 0.0, ceiling_m_ = 0.0, draw_radius_m_ = 0.0;
};

// Closed outline of an axis-aligned ceiling rectangle, edges subdivided.
std::vector<cv::Point3d> rectangle_outline(double x0_m, double y0_m, double x1_m, double y1_m,
                                           double z_m) {
  std::vector<cv::Point3d> out;
  const std::array<cv::Point2d, 5> corners{cv::Point2d(x0_m, y0_m), cv::Point2d(x1_m, y0_m),
                                           cv::Point2d(x1_m, y1_m), cv::Point2d(x0_m, y1_m),
                                           cv::Point2d(x0_m, y0_m)};
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d a = corners[k], b = corners[k + 1];
    const int steps = std::max(1, static_cast<int>(std::ceil(cv::norm(b - a) / kEdgeStep_m)));
    for (int t = 0; t < steps; ++t) {
      const cv::Point2d p = a + (b - a) * (static_cast<double>(t) / steps);
      out.emplace_back(p.x, p.y, z_m);
    }
  }
  return out;
}

// Sampled outline of a ceiling ellipse; its image is then a true projected
// conic (with distortion), not an image-space ellipse.
std::vector<cv::Point3d> ellipse_outline(double cx_m, double cy_m, double full_e_m, double full_n_m,
                                         double z_m) {
  constexpr int kSamples = 64;
  std::vector<cv::Point3d> out;
  for (int k = 0; k < kSamples; ++k) {
    const double t = 2.0 * CV_PI * k / kSamples;
    out.emplace_back(cx_m + 0.5 * full_e_m * std::cos(t), cy_m + 0.5 * full_n_m * std::sin(t), z_m);
  }
  return out;
}

void fill_world_polygon(const Projector& proj, const std::vector<cv::Point3d>& world, int ss,
                        const cv::Scalar& colour, cv::Mat* canvas) {
  const std::vector<cv::Point2d> image = proj.project(world);
  std::vector<cv::Point> fixed;
  fixed.reserve(image.size());
  const double scale = static_cast<double>(1 << kFixedPointShift);
  for (const cv::Point2d& p : image) {
    // Low-res pixel centre u maps to the supersampled pixel centre (u+0.5)ss-0.5.
    const double hu = (p.x + 0.5) * ss - 0.5, hv = (p.y + 0.5) * ss - 0.5;
    fixed.emplace_back(static_cast<int>(std::lround(hu * scale)),
                       static_cast<int>(std::lround(hv * scale)));
  }
  const cv::Point* pts = fixed.data();
  const int n = static_cast<int>(fixed.size());
  cv::fillPoly(*canvas, &pts, &n, 1, colour, cv::LINE_8, kFixedPointShift);
}

int code_bit(int code, int slot) { return (code >> (2 - slot)) & 1; }

void draw_marker(const Projector& proj, int i, int j, int ss, cv::Mat* canvas) {
  const double x_m = i * kGrid_m, y_m = j * kGrid_m, z_m = proj.ceiling_m();
  fill_world_polygon(proj,
                     rectangle_outline(x_m, y_m - 6 * kIn_m, x_m + 5 * kIn_m, y_m + 6 * kIn_m, z_m),
                     ss, kRed, canvas);
  fill_world_polygon(proj,
                     rectangle_outline(x_m - 5 * kIn_m, y_m - 6 * kIn_m, x_m, y_m + 6 * kIn_m, z_m),
                     ss, kGreen, canvas);
  for (int slot = 0; slot < 3; ++slot) {
    const double n_m = (4.0 - 4.0 * slot) * kIn_m;  // slot 0 northernmost, the MSB
    if (code_bit(i, slot)) {
      fill_world_polygon(proj,
                         ellipse_outline(x_m + 2.5 * kIn_m, y_m + n_m, 2 * kIn_m, 1 * kIn_m, z_m),
                         ss, kDot, canvas);
    }
    if (code_bit(j, slot)) {
      fill_world_polygon(proj,
                         ellipse_outline(x_m - 2.5 * kIn_m, y_m + n_m, 3 * kIn_m, 2 * kIn_m, z_m),
                         ss, kDot, canvas);
    }
  }
}

void draw_rails_and_fixtures(const Projector& proj, int ss, bool fixtures, cv::Mat* canvas) {
  const double r_m = proj.draw_radius_m(), z_m = proj.ceiling_m();
  const double x0 = proj.centre_x_m() - r_m, x1 = proj.centre_x_m() + r_m;
  const double y0 = proj.centre_y_m() - r_m, y1 = proj.centre_y_m() + r_m;
  const int i0 = static_cast<int>(std::floor(x0 / kGrid_m)),
            i1 = static_cast<int>(std::ceil(x1 / kGrid_m));
  const int j0 = static_cast<int>(std::floor(y0 / kGrid_m)),
            j1 = static_cast<int>(std::ceil(y1 / kGrid_m));
  if (fixtures) {
    // Bright panels in a sparse, fixed set of tiles, clear of the markers.
    for (int i = i0; i < i1; ++i) {
      for (int j = j0; j < j1; ++j) {
        const int pick = ((i * 7 + j * 3) % 5 + 5) % 5;
        if (pick != 0 && pick != 3) continue;
        const cv::Scalar colour = pick == 0 ? cv::Scalar(255, 255, 255) : cv::Scalar(255, 244, 210);
        const double cx_m = (i + 0.5) * kGrid_m, cy_m = (j + 0.5) * kGrid_m, half_m = 0.15;
        fill_world_polygon(
            proj,
            rectangle_outline(cx_m - half_m, cy_m - half_m, cx_m + half_m, cy_m + half_m, z_m), ss,
            colour, canvas);
      }
    }
  }
  const double half_rail_m = 0.5 * kIn_m;
  for (int i = i0; i <= i1; ++i) {
    fill_world_polygon(
        proj, rectangle_outline(i * kGrid_m - half_rail_m, y0, i * kGrid_m + half_rail_m, y1, z_m),
        ss, kRail, canvas);
  }
  for (int j = j0; j <= j1; ++j) {
    fill_world_polygon(
        proj, rectangle_outline(x0, j * kGrid_m - half_rail_m, x1, j * kGrid_m + half_rail_m, z_m),
        ss, kRail, canvas);
  }
}

bool near_camera(const Projector& proj, int i, int j) {
  return std::hypot(i * kGrid_m - proj.centre_x_m(), j * kGrid_m - proj.centre_y_m()) <
         proj.draw_radius_m() - 0.3;
}

// Camera colour response in sRGB values: white balance, gamma, then saturation about the
// luma, then additive Gaussian noise, rounded to 8 bits.
cv::Mat apply_response(const cv::Mat& rgb, const XRenderOptions& options) {
  const bool unit_gain = options.channel_gain == std::array<double, 3>{1.0, 1.0, 1.0};
  if (unit_gain && options.gamma == 1.0 && options.saturation == 1.0 &&
      options.noise_sigma == 0.0) {
    return rgb;
  }
  cv::Mat f;
  rgb.convertTo(f, CV_32FC3, 1.0 / 255.0);
  if (!unit_gain) {
    cv::multiply(
        f, cv::Scalar(options.channel_gain[0], options.channel_gain[1], options.channel_gain[2]),
        f);
    cv::min(f, 1.0, f);
  }
  if (options.gamma != 1.0) cv::pow(f, options.gamma, f);
  f *= 255.0;
  if (options.saturation != 1.0) {
    cv::Mat luma;
    cv::transform(f, luma, cv::Matx13f(0.299f, 0.587f, 0.114f));
    cv::Mat luma3;
    cv::merge(std::vector<cv::Mat>{luma, luma, luma}, luma3);
    f = luma3 + (f - luma3) * options.saturation;
  }
  if (options.blur_sigma_px > 0.0) {
    cv::GaussianBlur(f, f, cv::Size(), options.blur_sigma_px);
  }
  if (options.noise_sigma > 0.0) {
    cv::Mat noise(f.size(), f.type());
    cv::RNG rng(options.seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, options.noise_sigma);
    f += noise;
  }
  cv::Mat out;
  f.convertTo(out, CV_8UC3);  // saturating and rounding
  return out;
}

}  // namespace

cv::Mat render_rgb(const XCamera& camera, const XMount& mount, const XPose& robot,
                   const XRenderOptions& options) {
  const Projector proj(camera, mount, robot);
  const int ss = std::max(1, options.supersample);
  cv::Mat canvas(camera.height * ss, camera.width * ss, CV_8UC3, kTile);
  draw_rails_and_fixtures(proj, ss, options.light_fixtures, &canvas);
  for (int i = 0; i < kCodes; ++i) {
    for (int j = 0; j < kCodes; ++j) {
      if (near_camera(proj, i, j)) draw_marker(proj, i, j, ss, &canvas);
    }
  }
  cv::Mat small;
  cv::resize(canvas, small, cv::Size(camera.width, camera.height), 0, 0, cv::INTER_AREA);
  cv::Mat out = apply_response(small, options);
  if (options.jpeg_quality > 0) {
    std::vector<uint8_t> jpeg;
    cv::Mat bgr;
    cv::cvtColor(out, bgr, cv::COLOR_RGB2BGR);
    cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality});
    cv::cvtColor(cv::imdecode(jpeg, cv::IMREAD_COLOR), out, cv::COLOR_BGR2RGB);
  }
  return out;
}

std::vector<XVisibleMarker> whole_markers(const XCamera& camera, const XMount& mount,
                                          const XPose& robot) {
  const Projector proj(camera, mount, robot);
  std::vector<XVisibleMarker> out;
  for (int i = 0; i < kCodes; ++i) {
    for (int j = 0; j < kCodes; ++j) {
      if (!near_camera(proj, i, j)) continue;
      const double x_m = i * kGrid_m, y_m = j * kGrid_m, z_m = proj.ceiling_m();
      std::vector<cv::Point3d> outline = rectangle_outline(x_m - 5 * kIn_m, y_m - 6 * kIn_m,
                                                           x_m + 5 * kIn_m, y_m + 6 * kIn_m, z_m);
      outline.emplace_back(x_m, y_m, z_m);  // the centre, last
      const std::vector<cv::Point2d> image = proj.project(outline);
      const bool inside = std::all_of(image.begin(), image.end(), [&](const cv::Point2d& p) {
        return p.x >= 0.0 && p.y >= 0.0 && p.x <= camera.width - 1.0 && p.y <= camera.height - 1.0;
      });
      if (inside) out.push_back({i, j, image.back().x, image.back().y});
    }
  }
  return out;
}

cv::Point2d marker_centre_px(const XCamera& camera, const XMount& mount, const XPose& robot, int i,
                             int j) {
  const Projector proj(camera, mount, robot);
  return proj.project({cv::Point3d(i * kGrid_m, j * kGrid_m, proj.ceiling_m())}).front();
}

}  // namespace ceilpose::testing::xcheck
