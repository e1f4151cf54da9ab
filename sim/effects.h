#pragma once
// Photometric effects a real ceiling camera suffers, applied by the renderer
// on top of the geometric scene. Every field defaults to "clean".
#include <array>

namespace ceilpose::sim {

struct Effects {
  double gain = 1.0;                // exposure gain (auto-exposure), multiplies linear radiance
  double gradient_amplitude = 0.0;  // smooth illumination gradient, 0..1 relative
  double gradient_angle_rad = 0.0;  // image direction in which the illumination increases
  std::array<double, 3> white_balance{1.0, 1.0, 1.0};  // per-channel R,G,B colour cast multipliers
  double read_noise_sigma = 0.0;                       // Gaussian noise, 8-bit levels
  double shot_noise_scale = 0.0;  // Poisson-like noise, sigma = sqrt(scale*level)
  double defocus_sigma_px = 0.0;  // Gaussian blur
  double motion_blur_px = 0.0;    // linear motion blur length
  double motion_blur_angle_rad = 0.0;
  int jpeg_quality = 0;             // 0 = no JPEG round trip; else 1..100
  bool light_fixtures = true;       // saturated light panels on some tiles
  double bloom = 0.0;               // bloom strength around saturated fixtures
  double occlusion_fraction = 0.0;  // fraction of image covered by an occluder blob (dark)
  int clutter_objects = 0;          // red/green non-marker objects on the ceiling
};

}  // namespace ceilpose::sim
