#pragma once
// The ceiling of SPEC §1–2: grid, height, and the `thesis3` marker family.
// Everything here is geometry in metres; colours are sRGB as printed.
#include <array>
#include <cstdint>

#include "core/camera_model.h"
#include "core/image.h"

namespace ceilpose {

inline constexpr double kInch_m = 0.0254;
inline constexpr int kMaxBits = 8;

struct CeilingLayout {
  double height_m = 2.4384;  // ceiling plane z = H
  double grid_m = 0.6096;    // marker spacing g
  int bits = 3;              // bits per rectangle; codes 0 .. 2^bits - 1
  // Marker geometry in the marker frame (e East, n North), SPEC §2 table.
  double rect_width_m = 5.0 * kInch_m;    // E–W extent of each rectangle
  double rect_height_m = 12.0 * kInch_m;  // N–S extent
  double slot_pitch_m = 4.0 * kInch_m;
  double green_dot_e_m = 3.0 * kInch_m;  // full axes
  double green_dot_n_m = 2.0 * kInch_m;
  double red_dot_e_m = 2.0 * kInch_m;
  double red_dot_n_m = 1.0 * kInch_m;
  Rgb red{200, 30, 40};
  Rgb green{40, 160, 70};
  Rgb dot{25, 25, 25};
  Rgb tile{215, 215, 205};
  Rgb rail{170, 170, 170};
  double rail_width_m = 1.0 * kInch_m;

  int codes() const { return 1 << bits; }
  // Marker (i, j) centre in the world (SPEC §1).
  Vec3 marker_centre_w(int i, int j) const { return {i * grid_m, j * grid_m, height_m}; }
  // North coordinate of slot k (k = 0 is the northernmost slot, the MSB).
  double slot_n_m(int k) const { return ((bits - 1) * 0.5 - k) * slot_pitch_m; }
  // East coordinate of the red / green rectangle centre line.
  double red_centre_e_m() const { return 0.5 * rect_width_m; }
  double green_centre_e_m() const { return -0.5 * rect_width_m; }
  // Bit of `code` that slot k shows (MSB northernmost).
  bool slot_bit(int code, int k) const { return ((code >> (bits - 1 - k)) & 1) != 0; }
};

}  // namespace ceilpose
