#pragma once
// Stage 1: one sweep over the frame that classifies every pixel (fused
// lookup of color_classifier.h), run-length encodes each row and joins runs
// into 8-connected components with union-find, accumulating area, centroid
// and second central moments per component. Dark pixels enclosed left and
// right by one colour (the dots) count towards that colour's component, so a
// rectangle's moments are those of the whole rectangle, whatever its code.
// Allocates only in the constructor and resize(); one instance per pipeline.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/image.h"
#include "pipeline/color_classifier.h"
#include "pipeline/detector_params.h"

namespace ceilpose {

// A part of the frame to sweep: a box, pixels, inclusive bounds, and within
// it, when `quad` is set, only the convex quadrilateral (corners in order,
// pixel coordinates): a marker seen at 45° fills half its box.
struct PixelWindow {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool quad = false;
  std::array<float, 4> qu{}, qv{};
  bool empty() const { return x1 < x0 || y1 < y0; }
  int64_t area_px() const { return empty() ? 0 : int64_t{x1 - x0 + 1} * (y1 - y0 + 1); }
  // Row y's pixels inside the window, [*lo, *hi]; false when none.
  bool row_span(int y, int* lo, int* hi) const;
  bool operator==(const PixelWindow&) const = default;
};

struct Component {
  PixelClass cls = PixelClass::kBackground;
  int area_px = 0;  // pixels, dots included
  int dark_px = 0;  // enclosed dark pixels among area_px
  int x_min = 0, x_max = 0, y_min = 0, y_max = 0;
  // Some pixel lies on the outermost row/column of the frame, or of the
  // window it was found in (a tracked sweep): the blob may continue beyond.
  bool touches_border = false;
  // Centroid (pixel centres at integer coordinates, SPEC §3) and second
  // central moments per pixel: mu20 = E[(x−cx)²], mu11, mu02.
  double cx = 0.0, cy = 0.0;
  double mu20 = 0.0, mu11 = 0.0, mu02 = 0.0;

  // Orientation of the major axis from tan 2θ = 2·mu11 / (mu20 − mu02),
  // radians in (−π/2, π/2], image axes (u right, v down).
  double orientation_rad() const;
};

class ComponentLabeler {
 public:
  ComponentLabeler(int width_px, int height_px, const DetectorParams& params);

  // Re-allocates for another frame size (only when the size changes).
  void resize(int width_px, int height_px);
  int width_px() const { return width_; }
  int height_px() const { return height_; }

  // Labels one frame, which must have the size given at construction.
  // Returns false (and no components) when the frame exceeded the run
  // budget (`max_runs_per_pixel`): noise, not a ceiling. GRAY8 frames hold
  // no colour and give no components. Hot path: no allocation.
  bool label(const ImageView& frame, const ColorClassifier& classifier);
  // The same, within `windows` only (a tracked sweep): they must lie inside
  // the frame, their boxes neither overlapping nor touching (merge_windows),
  // else false and no components; the run budget is that of
  // the windows' pixels. A component on a window's edge touches_border.
  // The hot path of tracking: no allocation.
  bool label(const ImageView& frame, const ColorClassifier& classifier,
             std::span<const PixelWindow> windows);

  // The same over every step_px-th pixel of every step_px-th row (pixels
  // (s·i, s·j), s 2 or 4, else false): 1/s² of the pixels, to find the
  // markers when they are large enough to be seen so
  // (Pipeline::process_halved). Components are given in the frame's
  // pixels: centroid, extent, area and dark pixels scaled back, and the
  // second moments those of the frame's pixel grid (+(s²−1)/12 px²: a
  // lattice of step s holds that much less variance per axis than the
  // region it samples). A blob on the sampled grid's last row or column
  // touches the border. Hot path: no allocation.
  bool label_sampled(const ImageView& frame, const ColorClassifier& classifier, int step_px);

  std::span<const Component> components() const { return {comps_.data(), comp_count_}; }
  int run_count() const { return run_count_; }
  // Pixels the last sweep classified.
  int64_t swept_px() const { return swept_px_; }
  // Red or green blobs of a tracked sweep on a window edge inside the frame
  // (a marker where the windows did not expect it); 0 for a full sweep.
  int window_cut_count() const { return window_cuts_; }

 private:
  struct Run {
    int32_t x0, x1, y;
    int32_t dark_px;
    PixelClass cls;
    bool window_edge;  // starts or ends on a window's edge inside the frame
  };

  void classify_span(const ImageView& frame, int y, int x0, int x1,
                     const ColorClassifier& classifier);
  void classify_yuv_span(const ImageView& frame, int y, int x0, int x1,
                         const ColorClassifier& classifier);
  // The same, converting only the blocks of pixels not proven background
  // by the classifier's box (their classes stay 0).
  void classify_yuv_span_outside_box(const ImageView& frame, int y, int x0, int x1,
                                     const ColorClassifier& classifier);
  // Pixels (step_px·i, y), i < count, into row_class_[i]: each pixel with
  // its pair's own chroma (4:2:0: its chroma row's), no interpolation.
  void classify_sampled_row(const ImageView& frame, int y, int step_px, int count,
                            const ColorClassifier& classifier);
  // Row spans of every window, computed once per sweep (and, for a tracked
  // sweep, their pixels asked for); windows in the order of their left edges.
  void plan_spans(const ImageView& frame, std::span<const PixelWindow> windows, bool prefetch);
  // A sweep's counts emptied; whether the frame is refused (another size,
  // empty), has no colour to find (nothing to sweep) or is swept.
  enum class SweepStart { kRefused, kNoColour, kSweep };
  SweepStart begin_sweep(const ImageView& frame);
  // Runs of row y's classes in [x0, x1]; false, and no runs, past the run
  // budget.
  bool encode_row(int y, int x0, int x1);
  bool abandon();  // no runs; false
  // Joins the row just encoded (runs from cur_begin) to the one before,
  // then makes it the one before.
  void join_row(int cur_begin, int* prev_begin, int* prev_end);
  bool sweep_rows(const ImageView& frame, const ColorClassifier& classifier);
  void join_rows(int prev_begin, int prev_end, int cur_begin, int cur_end);
  int32_t find(int32_t i);
  void unite(int32_t a, int32_t b);
  // Components of the runs; the grid swept is width × height samples.
  void accumulate(int width, int height);

  DetectorParams params_;
  int width_ = 0;
  int height_ = 0;
  int max_runs_ = 0;
  int run_budget_ = 0;              // this sweep's: max_runs_, or the windows' share
  std::vector<uint8_t> row_class_;  // width + 8 bytes of padding
  std::vector<uint8_t> row_edge_;   // 1: a window's edge inside the frame (tracked sweeps)
  // A YUV span in stages, each a plain loop the compiler vectorises (SSE2,
  // NEON): per pair chroma ×4 (one pair of margin each side), per pixel
  // luma and chroma ×16, then the lookup index (the normalisation in
  // arithmetic, ColorClassifier::cell_of).
  std::vector<int16_t> pair_u_, pair_v_;
  std::vector<int16_t> px_y_, px_u_, px_v_;
  std::vector<uint32_t> px_index_;
  // Per sample of a sampled row (per pixel pair of a full-resolution
  // span): 1 where it lies in the classifier's background box (nothing to
  // convert or look up).
  std::vector<uint8_t> in_box_;
  struct RowSpan {
    int x0 = 0, x1 = -1;  // x1 < x0: none
  };
  struct SweptWindow {
    int x0, y0, y1;
    int32_t window;      // index in the caller's windows
    int32_t first_span;  // its row y0's span in spans_, then one per row
  };
  std::vector<RowSpan> spans_;
  std::vector<SweptWindow> swept_;
  std::vector<Run> runs_;
  std::vector<int32_t> parent_;
  std::vector<int32_t> label_;
  std::vector<Component> comps_;
  std::vector<std::array<double, 5>> sums_;  // Σx, Σy, Σx², Σxy, Σy² per component
  std::vector<uint8_t> window_edge_;         // per component: some run on a window's edge
  int run_count_ = 0;
  size_t comp_count_ = 0;
  int window_cuts_ = 0;
  int64_t swept_px_ = 0;
};

// Merges windows that overlap or touch into their bounding boxes, in place;
// returns how many remain (the first ones of `windows`).
int merge_windows(std::span<PixelWindow> windows, int count);

}  // namespace ceilpose
