#pragma once
// A box of camera YUV bytes in which every sample is background, proven
// under this frame's normalisation: a sweep may leave such samples
// unclassified (their class is already 0) and spend the conversion and the
// fused lookup on the rest only. Most of a ceiling frame is tile, so most
// samples fall in it (docs/pipeline_speed.md, session 32).
//
// The proof is exact, not statistical. Each BT.601 channel rises or falls
// monotonically with Y, U and V (core/pixel_read.h: shift and clamp keep
// order), and each normalisation table rises with its level, so the box's
// samples reach exactly the lookup cells in a box of cells whose corners
// come from the YUV box's corners; the box is background when no cell in
// that cell box is anything else, which a summed table of the lookup's
// non-background cells answers in eight reads.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ceilpose {

// Inclusive byte ranges of Y, U and V; empty() when no box was proven.
struct YuvBox {
  uint8_t y_lo = 1, y_hi = 0, u_lo = 1, u_hi = 0, v_lo = 1, v_hi = 0;
  bool empty() const { return y_lo > y_hi || u_lo > u_hi || v_lo > v_hi; }
  bool contains(int y, int u, int v) const {
    return y >= y_lo && y <= y_hi && u >= u_lo && u <= u_hi && v >= v_lo && v <= v_hi;
  }
};

class BackgroundCells {
 public:
  // `lut` is the classifier's 2^(3·bits) cell table, index r << 2b | g << b | b.
  void build(const uint8_t* lut, int bits_per_channel);

  // Whether every cell with qr in [r0, r1], qg in [g0, g1], qb in [b0, b1]
  // (inclusive, in range) is background.
  bool all_background(int r0, int r1, int g0, int g1, int b0, int b1) const;

  // The largest box around (y, u, v) grown face by face while proven
  // background through `tables` (the classifier's three normalisation
  // tables, each level's cell shifted into place); empty when the centre
  // itself is not background.
  YuvBox grow(const std::array<const uint32_t*, 3>& tables, int y, int u, int v) const;

 private:
  bool proven(const std::array<const uint32_t*, 3>& tables, const YuvBox& box) const;
  int at(int r, int g, int b) const {
    return count_[(static_cast<size_t>(r) * side_ + g) * side_ + b];
  }

  int bits_ = 0;
  int side_ = 0;  // cells a channel + 1: the summed table's leading zero row
  // count_[r][g][b]: non-background cells with qr < r, qg < g, qb < b.
  std::vector<int32_t> count_;
};

}  // namespace ceilpose
