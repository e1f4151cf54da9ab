#pragma once
// Stage 1a: colour classification of pixels into red / green / dark /
// background through one fused lookup, with thresholds that follow the
// frame's exposure and white balance. Single-threaded: one instance per
// pipeline, called from the processing thread only.
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "core/ceiling_layout.h"
#include "core/image.h"
#include "core/pixel_read.h"
#include "pipeline/background_box.h"
#include "pipeline/detector_params.h"

namespace ceilpose {

enum class PixelClass : uint8_t { kBackground = 0, kRed = 1, kGreen = 2, kDark = 3 };

class ColorClassifier {
 public:
  static constexpr int kBitsPerChannel = 6;
  static constexpr int kCells = 1 << kBitsPerChannel;
  // The range of the normalisation's gains, and the three gains in 16
  // fractional bits.
  static constexpr float kMinGain = 0.25f;
  static constexpr float kMaxGain = 4.0f;
  struct GainsQ16 {
    int32_t r, g, b;
  };

  // The cell (0..kCells - 1) of a raw level under a gain in 16 fractional
  // bits: the normalised level (rounded, at most 255) quantised. Level and
  // gain are bounded, so the product fits in 32 bits, which vectorises.
  static constexpr int cell_of(int level, int32_t gain_q16) {
    static_assert(255 * static_cast<int64_t>(kMaxGain * 65536.0f) + 32768 <= INT32_MAX);
    return std::min(kCells - 1, (level * gain_q16 + 32768) >> (16 + 8 - kBitsPerChannel));
  }
  // The lookup table's index of a colour's three cells.
  static constexpr uint32_t lut_index(int cell_r, int cell_g, int cell_b) {
    return static_cast<uint32_t>(cell_r) << (2 * kBitsPerChannel) |
           static_cast<uint32_t>(cell_g) << kBitsPerChannel | static_cast<uint32_t>(cell_b);
  }

  // Builds the lookup table (≈ 10 ms, 256 KiB). `tile` is the nominal tile
  // colour the frame is normalised to.
  ColorClassifier(const DetectorParams& params, Rgb tile);

  // Rebuilds the table for new thresholds (SIGHUP reload); not per frame.
  void set_params(const DetectorParams& params, Rgb tile);

  // Estimates the frame's tile reference from a sparse grid sample and sets
  // the per-channel normalisation from this frame alone. Returns false when
  // too few pixels looked like tile; the default normalisation (unit gains)
  // is then used, never an earlier frame's.
  bool adapt(const ImageView& frame);

  // Normalisation tables: table(c)[level] is the channel's cell (cell_of)
  // already shifted into its place in the lookup index, so that class =
  // lut()[table(0)[r] | table(1)[g] | table(2)[b]] = lut()[lut_index(cell_of
  // (r, gains_q16().r), ...)]: the tables for sparse reads, the arithmetic
  // for a sweep's vectors.
  const uint32_t* table(int channel) const { return tables_[channel].data(); }
  const uint8_t* lut() const { return lut_.data(); }
  const GainsQ16& gains_q16() const { return gains_q16_; }

  PixelClass classify(uint8_t r, uint8_t g, uint8_t b) const {
    return static_cast<PixelClass>(lut_[tables_[0][r] | tables_[1][g] | tables_[2][b]]);
  }
  // Classification of a pixel already in normalised levels (for tests and
  // for building the table).
  PixelClass classify_normalised(int r, int g, int b) const;

  // Current per-channel gains (normalised = raw × gain) and the measured
  // tile reference (raw levels) they came from. set_gains holds each gain
  // to kMinGain..kMaxGain, as adapt does.
  const std::array<float, 3>& gains() const { return gains_; }
  const std::array<float, 3>& reference() const { return reference_; }
  void set_gains(const std::array<float, 3>& gains);

  // Camera YUV bytes (BT.601, a sample's own chroma) that are background
  // under the current gains, around the tile's colour; proven with every
  // set_gains (pipeline/background_box.h). Empty when none is.
  const YuvBox& background_yuv() const { return background_yuv_; }

 private:
  void use_default_normalisation();
  uint32_t sample_candidates(const ImageView& frame, std::array<uint32_t, 256>* level_count,
                             uint32_t* total);
  uint32_t tile_colour_sum(uint32_t candidates, int median_level, std::array<double, 3>* sum) const;

  DetectorParams params_;
  Rgb tile_{};
  std::vector<uint8_t> lut_;
  std::array<std::array<uint32_t, 256>, 3> tables_{};
  std::array<float, 3> gains_{1.0f, 1.0f, 1.0f};
  GainsQ16 gains_q16_{65536, 65536, 65536};
  std::array<float, 3> reference_{};
  BackgroundCells background_cells_;
  YuvBox background_yuv_;
  std::array<uint32_t, 3 * 255 + 1> chroma_scale_{};
  // Tile candidates of the current frame's sample grid, R | G << 8 | B << 16.
  std::array<uint32_t, 8192> samples_{};
};

}  // namespace ceilpose
