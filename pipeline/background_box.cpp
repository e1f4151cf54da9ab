#include "pipeline/background_box.h"

#include <algorithm>
#include <cstdlib>

#include "core/pixel_read.h"

namespace ceilpose {
namespace {

// How far from the tile's colour a box may reach in U and V, levels: about
// three read-noise sigmas of a noisy camera's chroma.
constexpr int kChromaReach = 8;
// Luma levels a band proven at once spans at most (about two cells).
constexpr int kLumaBand = 8;

}  // namespace

void BackgroundCells::build(const uint8_t* lut, int bits_per_channel) {
  bits_ = bits_per_channel;
  const int cells = 1 << bits_;
  side_ = cells + 1;
  count_.assign(static_cast<size_t>(side_) * side_ * side_, 0);
  auto c = [&](int r, int g, int b) -> int32_t& {
    return count_[(static_cast<size_t>(r) * side_ + g) * side_ + b];
  };
  for (int r = 0; r < cells; ++r)
    for (int g = 0; g < cells; ++g)
      for (int b = 0; b < cells; ++b) {
        const size_t idx = (static_cast<size_t>(r) << (2 * bits_)) |
                           (static_cast<size_t>(g) << bits_) | static_cast<size_t>(b);
        const int32_t other = lut[idx] != 0 ? 1 : 0;
        c(r + 1, g + 1, b + 1) = other + c(r, g + 1, b + 1) + c(r + 1, g, b + 1) +
                                 c(r + 1, g + 1, b) - c(r, g, b + 1) - c(r, g + 1, b) -
                                 c(r + 1, g, b) + c(r, g, b);
      }
}

bool BackgroundCells::all_background(int r0, int r1, int g0, int g1, int b0, int b1) const {
  ++r1, ++g1, ++b1;
  const int others = at(r1, g1, b1) - at(r0, g1, b1) - at(r1, g0, b1) - at(r1, g1, b0) +
                     at(r0, g0, b1) + at(r0, g1, b0) + at(r1, g0, b0) - at(r0, g0, b0);
  return others == 0;
}

bool BackgroundCells::proven(const std::array<const uint32_t*, 3>& tables,
                             const YuvBox& box) const {
  // Each channel's least and greatest level over the box, at the corners
  // that minimise and maximise it (core/pixel_read.h's signs: r rises with
  // V, g falls with U and V, b rises with U; all rise with Y).
  const int luma_lo = yuv_luma_part(box.y_lo), luma_hi = yuv_luma_part(box.y_hi);
  const YuvChromaParts lo_lo = yuv_chroma_parts(box.u_lo, box.v_lo);
  const YuvChromaParts hi_hi = yuv_chroma_parts(box.u_hi, box.v_hi);
  const std::array<int, 3> level_lo{yuv_channel(luma_lo, lo_lo.r), yuv_channel(luma_lo, hi_hi.g),
                                    yuv_channel(luma_lo, lo_lo.b)};
  const std::array<int, 3> level_hi{yuv_channel(luma_hi, hi_hi.r), yuv_channel(luma_hi, lo_lo.g),
                                    yuv_channel(luma_hi, hi_hi.b)};
  std::array<int, 3> cell_lo{}, cell_hi{};
  const uint32_t mask = (1u << bits_) - 1;
  for (int c = 0; c < 3; ++c) {
    const int place = (2 - c) * bits_;
    cell_lo[c] = static_cast<int>(tables[c][level_lo[c]] >> place & mask);
    cell_hi[c] = static_cast<int>(tables[c][level_hi[c]] >> place & mask);
  }
  return all_background(cell_lo[0], cell_hi[0], cell_lo[1], cell_hi[1], cell_lo[2], cell_hi[2]);
}

YuvBox BackgroundCells::grow(const std::array<const uint32_t*, 3>& tables, int y, int u,
                             int v) const {
  if (count_.empty()) return {};
  auto byte = [](int x) { return static_cast<uint8_t>(std::clamp(x, 0, 255)); };
  YuvBox box{byte(y), byte(y), byte(u), byte(u), byte(v), byte(v)};
  if (!proven(tables, box)) return {};
  // Chroma first, a level at a time on each face in turn, at the tile's
  // luma alone.
  bool moved = true;
  while (moved) {
    moved = false;
    for (int face = 0; face < 4; ++face) {
      YuvBox next = box;
      uint8_t* end[] = {&next.u_lo, &next.u_hi, &next.v_lo, &next.v_hi};
      const int to = *end[face] + (face % 2 == 0 ? -1 : 1);
      if (to < 0 || to > 255 || std::abs(to - (face < 2 ? u : v)) > kChromaReach) continue;
      *end[face] = static_cast<uint8_t>(to);
      if (!proven(tables, next)) continue;
      box = next;
      moved = true;
    }
  }
  // Then luma, a band of levels at a time, each band proven on its own:
  // the box is the union of its bands. One cell box for the whole luma
  // range would let r come from its top and g from its bottom, a colour
  // no sample has, and stopped a box at +-9 levels.
  for (const int dir : {-1, 1}) {
    for (int step = kLumaBand; step >= 1;) {
      const int from = (dir < 0 ? box.y_lo : box.y_hi) + dir;
      const int to = from + dir * (step - 1);
      if (to < 0 || to > 255) {
        step /= 2;
        continue;
      }
      YuvBox band = box;
      band.y_lo = static_cast<uint8_t>(std::min(from, to));
      band.y_hi = static_cast<uint8_t>(std::max(from, to));
      if (!proven(tables, band)) {
        step /= 2;
        continue;
      }
      (dir < 0 ? box.y_lo : box.y_hi) = static_cast<uint8_t>(to);
    }
  }
  return box;
}

}  // namespace ceilpose
