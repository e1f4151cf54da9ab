#pragma once
// The camera side of the simulator: turns the linear-light radiance the
// renderer integrated per pixel into the 8-bit sRGB frame a real ceiling
// camera delivers, with the photometric effects of `Effects`.
#include <array>
#include <cstdint>
#include <vector>

#include "codec/jpeg_codec.h"
#include "core/image.h"
#include "sim/effects.h"

namespace ceilpose::sim {

class Photometry {
 public:
  Photometry();

  // Sizes every buffer for a width x height frame; the only call that
  // allocates (apply() calls it when the size changes).
  void resize(int width_px, int height_px);

  // `linear` holds width*height*3 floats (RGB, linear light, 1.0 = sensor
  // white at unit gain); it is used as scratch and left modified. Writes an
  // RGB24 frame of the same size into `out`. `rng_seed` drives the noise and
  // the occluder's shape and place. Allocates nothing once sized, except
  // inside libjpeg-turbo when jpeg_quality > 0.
  void apply(const Effects& effects, uint64_t rng_seed, float* linear, Image* out);

 private:
  void add_occluder(double fraction, uint64_t rng_seed, float* linear) const;
  void gaussian_blur(float* img, float* tmp, int width_px, int height_px, double sigma_px) const;
  void motion_blur(float* linear, double length_px, double angle_rad);
  void add_bloom(float* linear, double strength);
  void encode(const Effects& effects, uint64_t rng_seed, const float* linear, Image* out) const;
  void jpeg_round_trip(int quality, Image* out);

  int width_px_ = 0;
  int height_px_ = 0;
  std::vector<float> scratch_;  // full-frame temporary of a blur pass
  std::vector<float> small_;    // bloom at a quarter of the resolution
  std::vector<float> small_scratch_;
  std::vector<uint8_t> encode_u8_;   // linear -> sRGB, clean path
  std::vector<float> encode_f_;      // linear -> sRGB levels before noise
  std::vector<float> normal_table_;  // standard-normal quantiles, indexed by random bits
  codec::JpegCodec jpeg_;
  std::vector<uint8_t> jpeg_bytes_;
};

}  // namespace ceilpose::sim
