#pragma once
// Parameters of the detection stages (colour classification .. dot reading).
// One struct, defaults in one place; config/ceilpose.yaml mirrors them.
// Colour thresholds apply to *normalised* pixels: each frame is first scaled
// per channel so that its ceiling tile reads as the nominal tile colour of
// SPEC §2 (≈ 215, 215, 205), which makes them independent of exposure and
// white balance (see color_classifier.cpp).
namespace ceilpose {

struct DetectorParams {
  // --- colour classification (color_classifier.cpp) ---
  // A normalised pixel whose brightest channel is below this is "dark" (a
  // dot). Dots print at 25, the red and green rectangles at 200 and 160: the
  // default sits near the green/dot midpoint. Raise it if blurred dots read
  // as unset; lower it if shadows on rectangles split them. Cost: none.
  int dark_max_value = 90;
  // Minimum HSV saturation (max-min)/max of a red / green pixel. Pixels
  // below are tile, rails or fixtures. The defaults cut a red/tile and a
  // green/tile edge pixel at about the same coverage (≈ 40 % if the edge was
  // mixed in sRGB, ≈ 60 % if in linear light), so that both rectangles shrink
  // alike and the marker centre stays unbiased. Raise under strong coloured
  // light. Cost: none.
  float red_min_saturation = 0.33f;
  float green_min_saturation = 0.24f;
  // Red versus green is decided by r - g (normalised levels) against this
  // split: r - g is linear in the mix, so a pixel on the shared edge goes to
  // the rectangle that covers more of it. Cost: none.
  int red_green_split = 28;
  // Hue windows (degrees) that a saturated pixel must fall in to be red or
  // green; everything else saturated (blue, yellow clutter) is background.
  float red_hue_min_deg = -60.0f;  // i.e. 300°
  float red_hue_max_deg = 60.0f;
  float green_hue_min_deg = 25.0f;
  float green_hue_max_deg = 190.0f;
  // Grid step, in pixels, of the sparse sample that estimates the frame's
  // tile (white) reference. Smaller is steadier and costs more (about
  // width*height/step² pixel reads).
  int white_sample_step_px = 16;
  // Share of the sampled pixels that must look like tile for the estimate to
  // be trusted; otherwise the frame is classified with unit gains (counted),
  // never with an earlier frame's.
  float white_min_share = 0.05f;

  // --- connected components (components.cpp) ---
  // Upper bound of runs per frame as a share of the pixel count. A frame
  // with more (random noise) is abandoned: no markers, counted. Memory:
  // about 40 bytes per run, allocated once.
  float max_runs_per_pixel = 0.125f;

  // --- rectangle template fit (rectangle_fit.cpp) ---
  int min_rect_area_px = 150;  // smallest rectangle blob accepted, pixels
  // Accepted area as a fraction of the area the camera model predicts for a
  // rectangle (5 × 12 in seen from the nominal height). Widen for ceilings
  // of uneven height or strong tilt.
  float area_min_ratio = 0.55f;
  float area_max_ratio = 1.6f;
  // Accepted short/long side ratio (nominal 5/12 ≈ 0.417), from the blob's
  // second moments.
  float aspect_min = 0.28f;
  float aspect_max = 0.58f;
  // Accepted area / (long × short side from the moments): 1 for a filled
  // rectangle, lower for L-shapes and rings, higher for diamonds.
  float fill_min = 0.85f;
  float fill_max = 1.12f;

  // --- pairing red with green (marker_pairing.cpp) ---
  // Relative tolerance on the red–green centre distance (nominal: the
  // rectangle width, 5 in) and on the area ratio of the two rectangles.
  float pair_distance_tolerance = 0.3f;
  float pair_area_tolerance = 0.3f;
  // Relative tolerance on the two long sides: both rectangles span the same
  // 12 in, so a rectangle cut short by an occluder or glare differs.
  float pair_length_tolerance = 0.12f;
  // Largest angle (rad) between the two long axes, and between the
  // red→green vector and the normal of the red long axis.
  float pair_angle_tolerance_rad = 0.25f;

  // --- dot reading (dot_reader.cpp) ---
  // A slot holds a dot when its brightness is below this fraction of the
  // rectangle's own brightness (dot ≈ 0.13–0.16 of it when sharp, up to
  // ≈ 0.55 for a red dot under 1 px defocus plus 3 px motion blur; an empty
  // slot reads ≈ 1), on a sharp marker; blur raises it (below).
  float dot_threshold_ratio = 0.72f;
  // How far either side of its slot, along North (metres on the ceiling), a
  // dot's darkest line is searched. Covers centroid shifts from glare or
  // partial occlusion; must stay below pitch − dot height (2 in by default).
  // Cost: one line of three samples per pixel searched.
  double dot_search_m = 0.0254;
  // A marker is not decoded when any slot reads closer than this to the
  // threshold: a dot washed out by blur would otherwise read as unset, an
  // empty slot darkened by distortion or an occluder's edge as set, either
  // giving a valid-looking wrong code. Lower it to trade wrong codes for
  // availability.
  float dot_min_margin = 0.1f;
  // Blur washes dots towards their rectangle's brightness but leaves empty
  // slots at ≈ 1 (noise and JPEG ringing take them down to ≈ 0.82), so the
  // threshold rises by `dot_threshold_blur_shift` as the blur along North
  // (edge_spread_px, fraction of the red dot's height in pixels) goes from
  // `blur_shift_start` to `blur_shift_full`. Measured on the simulator: red
  // dots of 3 px (320×240) under defocus ≤ 1.2 px, motion ≤ 3 px, noise and
  // JPEG 60 read up to 0.88 at blur 0.5–0.7 of the dot, and with a fixed 0.72
  // such a dot could pass as unset (2 wrong codes in 336); sharp ones read
  // ≤ 0.47 even through JPEG, where empty slots dip to 0.77. The blur is
  // taken as hypot(edge spread, sampling_blur_px): the spread is measured on
  // the rectangle's darkest channel, while a 2–3 px dot also loses contrast
  // to pixel sampling and to the halved chroma of JPEG and YUYV (0.7 px
  // removed the wrong codes that dots shrunk to 2.2–2.7 px by lens
  // distortion at 320×240 still gave). See docs/detection.md.
  float dot_threshold_blur_shift = 0.1f;
  float blur_shift_start = 0.4f;
  float blur_shift_full = 0.6f;
  float sampling_blur_px = 0.7f;
  // A marker is not decoded when the blur along North (edge_spread_px at
  // the red rectangle's ends, 25–75 % rise) exceeds this fraction of the red
  // dot's height in pixels: such blur can wash a 1 in dot out completely,
  // and an unset slot then looks confidently unset. Sharp edges spread
  // 0.5 px; 640×480 frames under the stress levels measure ≤ 0.5 of the dot,
  // 320×240 ones mostly 0.4–0.7.
  float max_blur_to_dot = 0.75f;
  // A marker's quality (0..1, `MarkerObservation::quality`) is the product
  // of its dots' read margin over this margin (full quality at or above it)
  // and of its pairing score below quality_zero_pair_score (0 there). A lone
  // marker needs quality 0.5 to give a pose; lower this margin to trust
  // fainter dots.
  float quality_full_margin = 0.3f;
  float quality_zero_pair_score = 4.0f;

  // --- tracking (marker_tracking.cpp) ---
  // With the filter's fix, sweep only the windows where the markers will be
  // (issue 29); the whole frame when the fix is lost, when a window comes
  // back without its marker, and every full_sweep_every frames (1 s at 30
  // fps; 1 = never track; the daemon and `locate` sweep that frame whole
  // after its tracked pose, as a check: Localizer::check_scheduled). Markers entering the view need
  // no full sweep: every marker of the map the view can hold gets a window.
  bool tracking = true;
  // A tracked frame measured at the predicted markers' edges (in linear
  // light) and dots alone (no classification, no components: the
  // rectangles' centroids are not measured, and their dark-area check not
  // made); false: the labeler sweeps windows around them. Both are at
  // least as accurate as a whole sweep on every scenario set; the edges
  // cost about half (docs/pipeline_speed.md, docs/decisions.md). The
  // thesis's modes (axes, barycentric) sweep windows whatever it says: they
  // position from centroids (positions_from_centroids).
  bool track_edges = true;
  // With the filter on, in a mode that positions from the edges: a frame
  // swept whole finds its markers at half resolution (every other pixel of
  // every other row; every 4th of every 4th where red dots are >= 10 px,
  // Pipeline::sweep_step_px) and measures them at their edges and dots as a
  // tracked frame does, when its markers are large enough to be seen so
  // (Pipeline::halved_sweep_suits); a frame that gives no pose so is swept
  // again at full resolution. Without the filter (`locate`, the golden
  // recordings) whole sweeps stay full resolution. See docs/pipeline_speed.md.
  bool halve_whole_sweeps = true;
  int full_sweep_every = 30;
  // Window margin around a marker's predicted outline: this many pixels...
  float track_margin_px = 4.0f;
  // ...plus this many times the last one-frame prediction's error
  // (position, and yaw at the frame's corners).
  float track_margin_errors = 3.0f;
  // Windows covering more than this share of the frame: sweep it whole.
  float track_max_area_share = 0.6f;
};

}  // namespace ceilpose
