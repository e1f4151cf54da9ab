#include "pipeline/color_classifier.h"

#include <cmath>

// Method (issue 3, "thresholds that adapt to exposure and white balance").
//
// The thesis classified in HSV with fixed thresholds; auto-exposure and
// colour casts then moved the colours out of their windows. Here every frame
// is first normalised so that its ceiling tile reads as the nominal tile
// colour, and only then classified with fixed HSV-style rules:
//
//  1. White reference. A sparse grid (every `white_sample_step_px`-th pixel
//     of every step-th row, ≈ 1/256 of the frame) is read. Samples that are
//     neither dark (max < 40) nor colourful (HSV saturation > 0.35) are
//     tile, rails or fixtures; the tile covers most of any ceiling view, so
//     the median brightness of those samples is tile, and the mean R, G, B
//     of the samples within ±15 % of that median is the tile reference.
//     A camera gain g or a channel cast w multiplies linear light, which is
//     close to multiplying the 8-bit sRGB level by g^(1/2.2): one gain per
//     channel, gain_c = tile_c / reference_c, undoes both.
//  2. Fused lookup. Normalisation and classification are one table lookup
//     per pixel: three 256-entry tables map raw levels to normalised levels
//     quantised to 6 bits and shifted into place, and a 64³ table holds the
//     class of every normalised colour cell. The 64³ table depends only on
//     the thresholds (built once); adapting to a frame rewrites 768 entries.
//  3. Rules on the normalised colour (r, g, b), V = max, S = (V − min) / V:
//     V < dark_max_value → dark (dots);
//     else r − g > red_green_split → red if S and hue fit red;
//     else green if S and hue fit green; otherwise background.
//     r − g is linear in the mix of two printed colours, so a pixel on the
//     shared red/green edge goes to whichever rectangle covers more of it.
//
// Grey input (GRAY8) gives r = g = b: saturation 0, nothing is red or green.

namespace ceilpose {
namespace {

constexpr int kMinSampleLevel = 40;
constexpr float kMaxTileSaturation = 0.35f;
constexpr float kTileWindow = 0.15f;
constexpr float kMinGain = 0.25f;
constexpr float kMaxGain = 4.0f;

float hue_deg(int r, int g, int b, int v, int m) {
  const float d = static_cast<float>(v - m);
  if (d <= 0.0f) return 0.0f;
  float h = 0.0f;
  if (v == r) {
    h = 60.0f * static_cast<float>(g - b) / d;  // −60 .. 60 around red
  } else if (v == g) {
    h = 120.0f + 60.0f * static_cast<float>(b - r) / d;
  } else {
    h = 240.0f + 60.0f * static_cast<float>(r - g) / d;
  }
  return h;
}

}  // namespace

ColorClassifier::ColorClassifier(const DetectorParams& params, Rgb tile) {
  set_params(params, tile);
}

PixelClass ColorClassifier::classify_normalised(int r, int g, int b) const {
  const int v = std::max({r, g, b});
  const int m = std::min({r, g, b});
  if (v < params_.dark_max_value) return PixelClass::kDark;
  const float s = static_cast<float>(v - m) / static_cast<float>(v);
  float h = hue_deg(r, g, b, v, m);
  if (r - g > params_.red_green_split) {
    if (h > 180.0f) h -= 360.0f;  // red's window straddles 0°
    if (s >= params_.red_min_saturation && h >= params_.red_hue_min_deg &&
        h <= params_.red_hue_max_deg)
      return PixelClass::kRed;
    return PixelClass::kBackground;
  }
  if (h < 0.0f) h += 360.0f;
  if (s >= params_.green_min_saturation && h >= params_.green_hue_min_deg &&
      h <= params_.green_hue_max_deg)
    return PixelClass::kGreen;
  return PixelClass::kBackground;
}

void ColorClassifier::set_params(const DetectorParams& params, Rgb tile) {
  params_ = params;
  tile_ = tile;
  lut_.assign(static_cast<size_t>(kCells) * kCells * kCells, 0);
  // Each cell is classified at its centre level.
  constexpr int kStep = 256 / kCells;
  for (int qr = 0; qr < kCells; ++qr)
    for (int qg = 0; qg < kCells; ++qg)
      for (int qb = 0; qb < kCells; ++qb) {
        const size_t idx = (static_cast<size_t>(qr) << (2 * kBitsPerChannel)) |
                           (static_cast<size_t>(qg) << kBitsPerChannel) | qb;
        lut_[idx] = static_cast<uint8_t>(classify_normalised(
            qr * kStep + kStep / 2, qg * kStep + kStep / 2, qb * kStep + kStep / 2));
      }
  set_gains(gains_);
}

void ColorClassifier::set_gains(const std::array<float, 3>& gains) {
  gains_ = gains;
  constexpr int kShift = 8 - kBitsPerChannel;
  for (int c = 0; c < 3; ++c) {
    const int place = (2 - c) * kBitsPerChannel;
    // Fixed point (16 fractional bits) with rounding: 768 entries per frame.
    const auto gain_q16 = static_cast<int64_t>(gains_[c] * 65536.0f + 0.5f);
    for (int level = 0; level < 256; ++level) {
      const auto norm = std::min<int64_t>(255, (level * gain_q16 + 32768) >> 16);
      tables_[c][level] = static_cast<uint32_t>(norm >> kShift) << place;
    }
  }
}

bool ColorClassifier::adapt(const ImageView& frame) {
  if (frame.empty() || frame.format == PixelFormat::kMjpeg) return false;
  const int step = std::max(1, params_.white_sample_step_px);
  std::array<uint32_t, 256> count{};
  std::array<std::array<uint32_t, 256>, 3> sum{};
  uint32_t total = 0, candidates = 0;
  for (int y = step / 2; y < frame.height; y += step) {
    for (int x = step / 2; x < frame.width; x += step) {
      uint8_t r = 0, g = 0, b = 0;
      read_rgb(frame, x, y, &r, &g, &b);
      ++total;
      const int v = std::max({r, g, b});
      const int m = std::min({r, g, b});
      if (v < kMinSampleLevel) continue;
      if (static_cast<float>(v - m) > kMaxTileSaturation * static_cast<float>(v)) continue;
      ++count[v];
      sum[0][v] += r;
      sum[1][v] += g;
      sum[2][v] += b;
      ++candidates;
    }
  }
  if (total == 0 || static_cast<float>(candidates) < params_.white_min_share * total) return false;
  uint32_t seen = 0;
  int median = 0;
  for (; median < 255; ++median) {
    seen += count[median];
    if (2 * seen >= candidates) break;
  }
  const int lo = static_cast<int>(std::floor(median * (1.0f - kTileWindow)));
  const int hi = std::min(255, static_cast<int>(std::ceil(median * (1.0f + kTileWindow))));
  std::array<double, 3> acc{};
  double n = 0.0;
  for (int v = lo; v <= hi; ++v) {
    n += count[v];
    for (int c = 0; c < 3; ++c) acc[c] += sum[c][v];
  }
  if (n <= 0.0) return false;
  const std::array<float, 3> nominal{static_cast<float>(tile_.r), static_cast<float>(tile_.g),
                                     static_cast<float>(tile_.b)};
  std::array<float, 3> gains{};
  for (int c = 0; c < 3; ++c) {
    reference_[c] = static_cast<float>(acc[c] / n);
    gains[c] = std::clamp(nominal[c] / std::max(1.0f, reference_[c]), kMinGain, kMaxGain);
  }
  set_gains(gains);
  return true;
}

}  // namespace ceilpose
