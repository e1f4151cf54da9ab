#include "pipeline/color_classifier.h"

#include <cmath>
#include <cstdlib>

// Method: thresholds that adapt to exposure and white balance, because fixed
// ones were the thesis's main failure under changing light.
//
// The thesis classified in HSV with fixed thresholds; auto-exposure and
// colour casts then moved the colours out of their windows. Here every frame
// is first normalised so that its ceiling tile reads as the nominal tile
// colour, and only then classified with fixed HSV-style rules:
//
//  1. White reference, from this frame alone. A sparse grid (every
//     `white_sample_step_px`-th pixel of every step-th row, ≈ 1/256 of the
//     frame) is read. Samples that are neither dark (max < 40) nor clearly
//     marker-coloured (HSV saturation > 0.6) may be tile, rails, fixtures or
//     clutter; the tile covers most of any ceiling view, so the median of
//     their mean level (r + g + b) / 3 is tile. Within ±15 % of it, the
//     tile's chromaticity r / (r + g + b), b / (r + g + b) is the median of
//     those samples, and the mean R, G, B of the samples within ±10/255 of
//     it in both is the tile reference. The saturation cut is loose because
//     a cast saturates the tile itself: (1.35, 1, 0.65) on sRGB levels makes
//     it (255, 215, 133), saturation 0.48, while the printed red and green
//     stay above 0.66 under any cast up to ±35 % per channel (except green
//     under magenta, 0.48, which is then half as bright as the tile). What
//     the cut lets through is removed by the two windows: white fixtures
//     read brighter (mean 255 against the tile's ≤ 212 at the same gain)
//     and, under a cast, also have another chromaticity; clutter and
//     rails have another level or chromaticity. Too few samples left (fewer
//     than `white_min_share` of the grid) gives unit gains, never an
//     earlier frame's, so the classification of a frame never depends on
//     the frames before it (SPEC §5).
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
// Largest sample saturation (v - m) / v that may be tile: 3 / 5.
constexpr int kMaxTileSaturationNum = 3;
constexpr int kMaxTileSaturationDen = 5;
constexpr float kTileWindow = 0.15f;
constexpr int kTileChromaWindow = 10;

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

// Smallest bin at or below which half of the `total` counts lie.
int median_bin(const std::array<uint32_t, 256>& count, uint32_t total) {
  uint32_t seen = 0;
  int bin = 0;
  for (; bin < 255; ++bin) {
    seen += count[bin];
    if (2 * seen >= total) break;
  }
  return bin;
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
        lut_[lut_index(qr, qg, qb)] = static_cast<uint8_t>(classify_normalised(
            qr * kStep + kStep / 2, qg * kStep + kStep / 2, qb * kStep + kStep / 2));
      }
  background_cells_.build(lut_.data(), kBitsPerChannel);
  // 255 / sum in 16 fractional bits: two chromaticities per tile sample
  // without a division.
  chroma_scale_[0] = 0;
  for (int sum = 1; sum < static_cast<int>(chroma_scale_.size()); ++sum)
    chroma_scale_[sum] = static_cast<uint32_t>((255u << 16) / static_cast<unsigned>(sum));
  set_gains(gains_);
}

void ColorClassifier::set_gains(const std::array<float, 3>& gains) {
  for (int c = 0; c < 3; ++c) {
    // NaN to the least gain: std::clamp would pass it through.
    gains_[c] = gains[c] >= kMinGain ? std::min(gains[c], kMaxGain) : kMinGain;
  }
  // Fixed point (16 fractional bits) with rounding: 768 entries per frame.
  auto q16 = [](float gain) { return static_cast<int32_t>(gain * 65536.0f + 0.5f); };
  gains_q16_ = {q16(gains_[0]), q16(gains_[1]), q16(gains_[2])};
  for (int level = 0; level < 256; ++level) {
    tables_[0][level] = lut_index(cell_of(level, gains_q16_.r), 0, 0);
    tables_[1][level] = lut_index(0, cell_of(level, gains_q16_.g), 0);
    tables_[2][level] = lut_index(0, 0, cell_of(level, gains_q16_.b));
  }
  // Around the raw colour these gains take to the nominal tile: the tile.
  const Yuv tile = rgb_to_yuv(tile_.r / gains_[0], tile_.g / gains_[1], tile_.b / gains_[2]);
  background_yuv_ = background_cells_.grow({table(0), table(1), table(2)}, tile.y, tile.u, tile.v);
}

void ColorClassifier::use_default_normalisation() {
  reference_ = {static_cast<float>(tile_.r), static_cast<float>(tile_.g),
                static_cast<float>(tile_.b)};
  set_gains({1.0f, 1.0f, 1.0f});
}

// 1. A grid of samples (coarser when the frame has more grid points than the
// buffer holds, above about 1920 x 1080 at step 16); the bright, unsaturated
// ones are tile candidates, kept packed for the later passes, with a
// histogram of their levels.
uint32_t ColorClassifier::sample_candidates(const ImageView& frame,
                                            std::array<uint32_t, 256>* level_count,
                                            uint32_t* total) {
  int step = std::max(1, params_.white_sample_step_px);
  while (static_cast<size_t>((frame.width + step - 1) / step) * ((frame.height + step - 1) / step) >
         samples_.size())
    ++step;
  uint32_t candidates = 0;
  *total = 0;
  // One dispatch on the format for the frame's grid (MJPEG: no pixels).
  with_pixel_reader(frame.format, [&](auto read) {
    for (int y = step / 2; y < frame.height; y += step)
      for (int x = step / 2; x < frame.width; x += step) {
        const Rgb c = read(frame, x, y);
        const int r = c.r, g = c.g, b = c.b;
        ++*total;
        const int v = std::max({r, g, b});
        const int m = std::min({r, g, b});
        // Saturation (v - m) / v at most kMaxTileSaturationNum / Den.
        if (v < kMinSampleLevel || (v - m) * kMaxTileSaturationDen > v * kMaxTileSaturationNum)
          continue;
        ++(*level_count)[(r + g + b) / 3];
        samples_[candidates++] = static_cast<uint32_t>(r) | static_cast<uint32_t>(g) << 8 |
                                 static_cast<uint32_t>(b) << 16;
      }
  });
  return candidates;
}

// 2. Of the candidates within the brightness window around the median level,
// those within the chromaticity window around the median chromaticity: the
// tile, robust to strong casts and to coloured clutter. Their summed colour
// in *sum; returns how many.
uint32_t ColorClassifier::tile_colour_sum(uint32_t candidates, int median_level,
                                          std::array<double, 3>* sum) const {
  const int lo_sum = 3 * static_cast<int>(std::floor(median_level * (1.0f - kTileWindow)));
  const int hi_sum = 3 * static_cast<int>(std::ceil(median_level * (1.0f + kTileWindow))) + 2;
  // Visits the candidates within the window with their chromaticities
  // c / (r + g + b) in 1/255 steps (r and b fix g).
  const auto for_each_windowed = [&](auto&& visit) {
    for (uint32_t k = 0; k < candidates; ++k) {
      const int r = static_cast<int>(samples_[k] & 0xff);
      const int g = static_cast<int>(samples_[k] >> 8 & 0xff);
      const int b = static_cast<int>(samples_[k] >> 16);
      const int level_sum = r + g + b;
      if (level_sum < lo_sum || level_sum > hi_sum) continue;
      const uint32_t scale = chroma_scale_[level_sum];
      visit(r, g, b, static_cast<int>((static_cast<uint32_t>(r) * scale) >> 16),
            static_cast<int>((static_cast<uint32_t>(b) * scale) >> 16));
    }
  };
  std::array<std::array<uint32_t, 256>, 2> chroma_count{};
  uint32_t windowed = 0;
  for_each_windowed([&](int, int, int, int chroma_r, int chroma_b) {
    ++chroma_count[0][chroma_r];
    ++chroma_count[1][chroma_b];
    ++windowed;
  });
  const int median_r = median_bin(chroma_count[0], windowed);
  const int median_b = median_bin(chroma_count[1], windowed);
  uint32_t n = 0;
  for_each_windowed([&](int r, int g, int b, int chroma_r, int chroma_b) {
    if (std::abs(chroma_r - median_r) > kTileChromaWindow ||
        std::abs(chroma_b - median_b) > kTileChromaWindow)
      return;
    (*sum)[0] += r;
    (*sum)[1] += g;
    (*sum)[2] += b;
    ++n;
  });
  return n;
}

bool ColorClassifier::adapt(const ImageView& frame) {
  if (frame.empty() || frame.format == PixelFormat::kMjpeg) {
    use_default_normalisation();
    return false;
  }
  std::array<uint32_t, 256> level_count{};
  uint32_t total = 0;
  const uint32_t candidates = sample_candidates(frame, &level_count, &total);
  if (total == 0 || static_cast<float>(candidates) < params_.white_min_share * total) {
    use_default_normalisation();
    return false;
  }
  std::array<double, 3> sum{};
  const uint32_t n = tile_colour_sum(candidates, median_bin(level_count, candidates), &sum);
  if (n == 0 || static_cast<float>(n) < params_.white_min_share * total) {
    use_default_normalisation();
    return false;
  }
  // 3. Gains that take the measured tile to its nominal colour.
  const std::array<float, 3> nominal{static_cast<float>(tile_.r), static_cast<float>(tile_.g),
                                     static_cast<float>(tile_.b)};
  std::array<float, 3> gains{};
  for (int c = 0; c < 3; ++c) {
    reference_[c] = static_cast<float>(sum[c] / n);
    gains[c] = std::clamp(nominal[c] / std::max(1.0f, reference_[c]), kMinGain, kMaxGain);
  }
  set_gains(gains);
  return true;
}

}  // namespace ceilpose
