#pragma once
// A second ceiling renderer written from SPEC.md's text alone, to cross-check
// the pipeline against frames that do not share sim/'s or core/'s reading of
// the contract. It deliberately includes nothing from core/ or sim/: the
// world->camera transform is re-derived from SPEC §3's axis formulas and the
// projection is OpenCV's own cv::projectPoints. It draws differently too:
// supersampled filled polygons, then an area-averaging downscale.
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace ceilpose::testing::xcheck {

// SPEC §3 pinhole + plumb_bob camera.
struct XCamera {
  int width = 640;
  int height = 480;
  double fx = 530.0;
  double fy = 530.0;
  double cx = 319.5;
  double cy = 239.5;
  std::array<double, 5> distortion{0.0, 0.0, 0.0, 0.0, 0.0};  // k1 k2 p1 p2 k3
};

// Where the camera sits on the robot: lens height, offset in the robot frame
// (forward, left) and the yaw of the image-up direction relative to the
// robot's forward axis, counter-clockwise. The ceiling height (SPEC §1's H)
// lives here too because only the lens-to-ceiling distance shapes the image.
struct XMount {
  double lens_height_m = 0.3048;
  double ceiling_height_m = 2.4384;
  double offset_forward_m = 0.0;
  double offset_left_m = 0.0;
  double yaw_rad = 0.0;
  // Tilt of the camera about its own image-right axis, then about its
  // image-down axis (SPEC §3: the axes rotate about the optical centre).
  double tilt_x_rad = 0.0;
  double tilt_y_rad = 0.0;
};

// How the frame departs from the ideal print: supersampling factor, a camera
// colour response (white balance, gamma and saturation applied to sRGB values), additive
// Gaussian noise and light fixtures in some tiles.
struct XRenderOptions {
  int supersample = 4;
  double gamma = 1.0;
  double saturation = 1.0;
  double noise_sigma = 0.0;
  std::array<double, 3> channel_gain{1.0, 1.0, 1.0};  // R G B white balance
  double blur_sigma_px = 0.0;                         // Gaussian defocus, before noise
  int jpeg_quality = 0;  // > 0: JPEG round trip last, as an MJPEG camera
  bool light_fixtures = true;
  uint64_t seed = 1;
};

struct XPose {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

// A marker whose entire outline projects inside the image (SPEC §6).
struct XVisibleMarker {
  int i = 0;
  int j = 0;
  double centre_u_px = 0.0;
  double centre_v_px = 0.0;
};

// Renders the default `thesis3` ceiling (8 x 8 markers, g = 0.6096 m, at
// mount.ceiling_height_m) seen from `robot`. Returns an 8-bit RGB (R first) image.
cv::Mat render_rgb(const XCamera& camera, const XMount& mount, const XPose& robot,
                   const XRenderOptions& options);

// Markers wholly inside the image for that pose, with their projected centres.
std::vector<XVisibleMarker> whole_markers(const XCamera& camera, const XMount& mount,
                                          const XPose& robot);

// Image of marker (i, j)'s centre (any marker, in view or not).
cv::Point2d marker_centre_px(const XCamera& camera, const XMount& mount, const XPose& robot, int i,
                             int j);

}  // namespace ceilpose::testing::xcheck
