#pragma once
// Stage 4: the marker's frame in the image (Heading) and its code (Read_Dots).
// The red→green vector is West; North follows from it; the dots are read
// slot by slot, most significant bit northernmost (SPEC §2).
#include <algorithm>
#include <array>
#include <cmath>

#include "core/ceiling_layout.h"
#include "core/image.h"
#include "core/int_rounding.h"
#include "pipeline/detector_params.h"
#include "pipeline/rectangle_fit.h"

namespace ceilpose {

// Affine image frame of one marker: marker point (e, n) in metres lands at
// (centre_u + e·east_u + n·north_u, centre_v + e·east_v + n·north_v).
struct MarkerFrame {
  double centre_u_px = 0.0, centre_v_px = 0.0;
  double east_u = 0.0, east_v = 0.0;    // pixels per metre East
  double north_u = 0.0, north_v = 0.0;  // pixels per metre North
  double west_image_rad = 0.0;          // image angle of West (red→green)

  void project(double e_m, double n_m, double* u_px, double* v_px) const {
    *u_px = centre_u_px + e_m * east_u + n_m * north_u;
    *v_px = centre_v_px + e_m * east_v + n_m * north_v;
  }
};

MarkerFrame marker_frame(const RectangleCandidate& red, const RectangleCandidate& green,
                         const CeilingLayout& layout);

// The pixels of a width × height frame within marker-frame rectangle
// e ∈ [e0_m, e1_m], n ∈ [n0_m, n1_m] and those a bilinear read inside it
// touches beyond it: rows first_row..last_row, each the columns its row()
// spans (x0 > x1: none).
struct PixelSpan {
  int x0 = 0, x1 = -1;
};
class MarkerRegion {
 public:
  MarkerRegion(const MarkerFrame& marker, double e0_m, double e1_m, double n0_m, double n1_m,
               int width, int height);
  int first_row() const { return first_row_; }
  int last_row() const { return last_row_; }
  // Inline: a tracked 1280x960 frame asks for ~3000 rows.
  PixelSpan row(int y) const {
    double u_lo = 0.0, u_hi = 0.0;
    PixelSpan out;
    if (!columns(y, &u_lo, &u_hi)) return out;
    // Clamped first: a span beyond the frame comes out empty (x0 > x1).
    out.x0 = floor_int(std::clamp(u_lo, 0.0, static_cast<double>(width_)));
    out.x1 = ceil_int(std::clamp(u_hi, -1.0, width_ - 1.0));
    return out;
  }
  // Calls fn(y, x0, x1) for each row from first_row() to last_row() whose
  // span row(y) is not empty, for prefetching: its x0 or one less, and its
  // x1 or one more. Truncated rather than rounded up (session 43), and each
  // bound's columns moved on by its slope a row rather than multiplied out
  // as columns(y) does, which rounds differently by ~1e-13 px (session 44:
  // docs/pipeline_speed.md).
  template <typename Fn>
  void for_each_span(Fn fn) const {
    const double width = width_, last_x = width_ - 1.0;
    const Bound& a = bounds_[0];
    const Bound& b = bounds_[1];
    const double dv = first_row_ - centre_v_px_;
    double a_lo = centre_u_px_ + (a.lo_px + dv * a.slope);
    double a_hi = centre_u_px_ + (a.hi_px + dv * a.slope);
    double b_lo = centre_u_px_ + (b.lo_px + dv * b.slope);
    double b_hi = centre_u_px_ + (b.hi_px + dv * b.slope);
    for (int y = first_row_; y <= last_row_;
         ++y, a_lo += a.slope, a_hi += a.slope, b_lo += b.slope, b_hi += b.slope) {
      const double lo = std::max(a_lo, b_lo), hi = std::min(a_hi, b_hi);
      if (!(lo <= hi) || !(hi > -1.0) || !(lo < width)) continue;
      // Both in [0, width − 1]: truncation is the floor.
      const int x0 = static_cast<int>(std::clamp(lo, 0.0, last_x));
      const int x1 = std::min(static_cast<int>(std::clamp(hi, 0.0, last_x)) + 1, width_ - 1);
      fn(y, x0, x1);
    }
  }

 private:
  // One of the rectangle's two coordinates (e, n) within its limits, on
  // the row dv below the centre: the columns du (from the centre's)
  // lo_px + dv·slope ≤ du ≤ hi_px + dv·slope. A coordinate that does not
  // change along rows bounds the rows alone, as the corners' rows already
  // do: every column (±infinity).
  struct Bound {
    double lo_px = -INFINITY, hi_px = INFINITY, slope = 0.0;
  };
  // The columns [*u_lo, *u_hi] of row y within both bounds, unclamped;
  // false when none (NaN bounds included).
  bool columns(int y, double* u_lo, double* u_hi) const {
    const double dv = y - centre_v_px_;
    const Bound& a = bounds_[0];
    const Bound& b = bounds_[1];
    const double du_lo = std::max(a.lo_px + dv * a.slope, b.lo_px + dv * b.slope);
    const double du_hi = std::min(a.hi_px + dv * a.slope, b.hi_px + dv * b.slope);
    *u_lo = centre_u_px_ + du_lo;
    *u_hi = centre_u_px_ + du_hi;
    return du_lo <= du_hi;
  }
  double centre_u_px_ = 0.0, centre_v_px_ = 0.0;
  std::array<Bound, 2> bounds_{};
  int width_ = 0;
  int first_row_ = 0, last_row_ = -1;
};

// Asks the memory system (a prefetch hint: no effect on results) for a
// MarkerRegion's pixels of the frame: row by row, only the span the
// rectangle's image crosses.
void ask_marker_region(const ImageView& frame, const MarkerFrame& marker, double e0_m, double e1_m,
                       double n0_m, double n1_m);

struct CodeReading {
  bool ok = false;                      // every sample inside the frame and a usable reference
  int code = 0;                         // 0 .. 2^bits − 1
  float margin = 0.0f;                  // smallest distance of a slot's ratio to the threshold
  std::array<float, kMaxBits> ratio{};  // slot brightness / rectangle brightness, MSB first
};

// The dot threshold for a marker whose red rectangle's ends spread
// `blur_px` (rectangle_ends.h's edge_spread_px; negative: unmeasured, taken as sharp) with red
// dots `red_dot_px` tall: params.dot_threshold_ratio raised with the blur
// (see DetectorParams::dot_threshold_blur_shift).
float dot_threshold_ratio(const DetectorParams& params, double blur_px, double red_dot_px);

// How a marker's dots are sought, by what placed its marker frame.
enum class DotSearch {
  // Its rectangles' centroids, which blur and glare move: each dot's
  // darkest line within ±params.dot_search_m along North of its slot,
  // against reference patches of 3 × 3 points.
  kFromCentroids,
  // Its edges, to a pixel (tracked frames, halved sweeps): within a
  // quarter inch (dot_reader.cpp's kEdgePlacedDotSearch_m), against
  // reference patches of one line of three points across the rectangle
  // (a patch's ±0.1 dot heights along North are under a pixel at 640×480;
  // its two rows more were 12 of a red rectangle's 45 samples).
  kFromEdges,
};

// Reads the `layout.bits` slots of the red (x code) or green (y code)
// rectangle against `threshold_ratio` (dot_threshold_ratio()). Sparse reads
// of the original frame: no allocation.
CodeReading read_code(const ImageView& frame, const MarkerFrame& marker, bool red,
                      const CeilingLayout& layout, const DetectorParams& params,
                      float threshold_ratio, DotSearch search = DotSearch::kFromCentroids);

// Whether the dark pixels found inside a rectangle fit the dots its code
// says it has: more dark area than the dots plus slack means dirt, an
// occluder or a foreign pattern, not a marker.
bool dark_area_consistent(const RectangleCandidate& rect, int code, bool red,
                          const CeilingLayout& layout, double px_per_m);

}  // namespace ceilpose
