#include "pipeline/rectangle_fit.h"

#include <algorithm>
#include <array>
#include <cmath>

// A filled a × b rectangle has central moments a²/12 and b²/12 along its
// axes. The eigenvalues λ1 ≥ λ2 of the blob's moment matrix
//   λ = (mu20 + mu02)/2 ± sqrt(((mu20 − mu02)/2)² + mu11²)
// therefore give its sides as sqrt(12 λ + 1): the +1 restores the 1/12 that
// each unit pixel square adds to the continuous moment and that the pixel
// centres miss. The long axis lies along θ with tan 2θ = 2 mu11/(mu20 − mu02)
// (the thesis's orientation formula). Fill = area / (long × short) is 1 for a
// filled rectangle and falls for rings, L-shapes and joined blobs.

// Lens distortion (SPEC §3, plumb_bob). The pixel map D from the ideal
// pinhole image p to the frame is smooth, so around a blob it is linear to
// first order: a rectangle stays a parallelogram, its moment matrix is
// C = J Cp Jᵀ and its area A = det J · Ap, with J = ∂D/∂p at the centroid.
// The shape tests therefore run on Cp = J⁻¹ C J⁻ᵀ and Ap = A / det J. To
// second order the frame's area centroid is not D(p0) of the true centre
// p0 but
//   c ≈ D(p0) + J Cp ∇w / w + ½ (tr(Hu Cp), tr(Hv Cp)),
// where w = det J weighs the frame's pixel area and Hu, Hv are D's
// Hessians; the fit subtracts that shift so the points handed to
// positioning are projections of the rectangle centres. All derivatives
// by central differences over 1 px.

namespace ceilpose {
namespace {

struct Vec2 {
  double u, v;
};

Vec2 distort_px(const CameraIntrinsics& k, double pu, double pv) {
  double xd = 0.0, yd = 0.0;
  distort_normalized(k, (pu - k.cx) / k.fx, (pv - k.cy) / k.fy, &xd, &yd);
  return {k.fx * xd + k.cx, k.fy * yd + k.cy};
}

// J = ∂D/∂p at p, row-major [du/dpu du/dpv; dv/dpu dv/dpv].
std::array<double, 4> jacobian(const CameraIntrinsics& k, double pu, double pv) {
  const Vec2 a = distort_px(k, pu + 1.0, pv), b = distort_px(k, pu - 1.0, pv);
  const Vec2 c = distort_px(k, pu, pv + 1.0), d = distort_px(k, pu, pv - 1.0);
  return {0.5 * (a.u - b.u), 0.5 * (c.u - d.u), 0.5 * (a.v - b.v), 0.5 * (c.v - d.v)};
}

double det(const std::array<double, 4>& j) { return j[0] * j[3] - j[1] * j[2]; }

struct LocalDistortion {
  std::array<double, 4> j;  // Jacobian at p0
  // Cp = J⁻¹ C J⁻ᵀ (symmetric: c20, c11, c02)
  double c20 = 0.0, c11 = 0.0, c02 = 0.0;
  double area_scale = 1.0;  // det J
  Vec2 shift{0.0, 0.0};     // frame centroid minus D(p0)
};

LocalDistortion local_distortion(const CameraIntrinsics& k, const Component& c) {
  LocalDistortion l;
  double xn = 0.0, yn = 0.0;
  undistort_pixel(k, c.cx, c.cy, &xn, &yn);
  const double pu = k.fx * xn + k.cx, pv = k.fy * yn + k.cy;
  l.j = jacobian(k, pu, pv);
  l.area_scale = det(l.j);
  const double id = 1.0 / l.area_scale;
  const std::array<double, 4> ji{l.j[3] * id, -l.j[1] * id, -l.j[2] * id, l.j[0] * id};
  // Cp = Ji C Jiᵀ with C = [mu20 mu11; mu11 mu02].
  const double a0 = ji[0] * c.mu20 + ji[1] * c.mu11, a1 = ji[0] * c.mu11 + ji[1] * c.mu02;
  const double b0 = ji[2] * c.mu20 + ji[3] * c.mu11, b1 = ji[2] * c.mu11 + ji[3] * c.mu02;
  l.c20 = a0 * ji[0] + a1 * ji[1];
  l.c11 = a0 * ji[2] + a1 * ji[3];
  l.c02 = b0 * ji[2] + b1 * ji[3];
  // Second-order centroid shift.
  const Vec2 d0 = distort_px(k, pu, pv);
  const Vec2 du_p = distort_px(k, pu + 1.0, pv), du_m = distort_px(k, pu - 1.0, pv);
  const Vec2 dv_p = distort_px(k, pu, pv + 1.0), dv_m = distort_px(k, pu, pv - 1.0);
  const Vec2 dpp = distort_px(k, pu + 1.0, pv + 1.0), dpm = distort_px(k, pu + 1.0, pv - 1.0);
  const Vec2 dmp = distort_px(k, pu - 1.0, pv + 1.0), dmm = distort_px(k, pu - 1.0, pv - 1.0);
  const double hu_uu = du_p.u - 2.0 * d0.u + du_m.u, hu_vv = dv_p.u - 2.0 * d0.u + dv_m.u;
  const double hu_uv = 0.25 * (dpp.u - dpm.u - dmp.u + dmm.u);
  const double hv_uu = du_p.v - 2.0 * d0.v + du_m.v, hv_vv = dv_p.v - 2.0 * d0.v + dv_m.v;
  const double hv_uv = 0.25 * (dpp.v - dpm.v - dmp.v + dmm.v);
  const double gw_u = 0.5 * (det(jacobian(k, pu + 1.0, pv)) - det(jacobian(k, pu - 1.0, pv)));
  const double gw_v = 0.5 * (det(jacobian(k, pu, pv + 1.0)) - det(jacobian(k, pu, pv - 1.0)));
  // Cp ∇w / w, then through J.
  const double q_u = (l.c20 * gw_u + l.c11 * gw_v) / l.area_scale;
  const double q_v = (l.c11 * gw_u + l.c02 * gw_v) / l.area_scale;
  l.shift.u =
      l.j[0] * q_u + l.j[1] * q_v + 0.5 * (hu_uu * l.c20 + 2.0 * hu_uv * l.c11 + hu_vv * l.c02);
  l.shift.v =
      l.j[2] * q_u + l.j[3] * q_v + 0.5 * (hv_uu * l.c20 + 2.0 * hv_uv * l.c11 + hv_vv * l.c02);
  return l;
}

// Sides of the rectangle with central moments (m20, m11, m02):
// sqrt(12 λ + 1) for each eigenvalue λ.
void sides(double m20, double m11, double m02, double* long_px, double* short_px) {
  const double mean = 0.5 * (m20 + m02);
  const double half_diff = 0.5 * (m20 - m02);
  const double root = std::sqrt(half_diff * half_diff + m11 * m11);
  *long_px = std::sqrt(12.0 * (mean + root) + 1.0);
  *short_px = std::sqrt(std::max(0.0, 12.0 * (mean - root) + 1.0));
}

}  // namespace

RectangleModel make_rectangle_model(const CameraIntrinsics& intrinsics, const CameraMount& mount,
                                    const CeilingLayout& layout) {
  RectangleModel m;
  const double distance_m = std::max(1e-3, layout.height_m - mount.lens_height_m);
  m.px_per_m = 0.5 * (intrinsics.fx + intrinsics.fy) / distance_m;
  m.expected_long_px = layout.rect_height_m * m.px_per_m;
  m.expected_short_px = layout.rect_width_m * m.px_per_m;
  m.expected_area_px = m.expected_long_px * m.expected_short_px;
  m.intrinsics = intrinsics;
  m.distorted = intrinsics.has_distortion();
  return m;
}

int fit_rectangles(std::span<const Component> components, const RectangleModel& model,
                   const DetectorParams& params, std::span<RectangleCandidate> out) {
  const double min_area =
      std::max<double>(params.min_rect_area_px, params.area_min_ratio * model.expected_area_px);
  const double max_area = params.area_max_ratio * model.expected_area_px;
  int count = 0;
  for (size_t k = 0; k < components.size() && count < static_cast<int>(out.size()); ++k) {
    const Component& c = components[k];
    if (c.cls != PixelClass::kRed && c.cls != PixelClass::kGreen) continue;
    // Distortion scales areas by det J, well within 4x for any usable lens:
    // a cheap first cut before the local model is computed.
    if (c.area_px < 0.25 * min_area || c.area_px > 4.0 * max_area) continue;
    // Shape tests in the undistorted image (identity without distortion).
    LocalDistortion l;
    l.c20 = c.mu20, l.c11 = c.mu11, l.c02 = c.mu02;
    if (model.distorted) l = local_distortion(model.intrinsics, c);
    const double area_px = c.area_px / l.area_scale;
    if (area_px < min_area || area_px > max_area) continue;
    double long_px = 0.0, short_px = 0.0;
    sides(l.c20, l.c11, l.c02, &long_px, &short_px);
    if (short_px <= 0.0) continue;
    const double aspect = short_px / long_px;
    if (aspect < params.aspect_min || aspect > params.aspect_max) continue;
    const double fill = area_px / (long_px * short_px);
    if (fill < params.fill_min || fill > params.fill_max) continue;
    RectangleCandidate& r = out[count++];
    r.cls = c.cls;
    r.component = static_cast<int>(k);
    r.cx = c.cx - l.shift.u;
    r.cy = c.cy - l.shift.v;
    // Axes and sides as seen in the frame, where pairing and dot reading
    // work.
    r.axis_rad = c.orientation_rad();
    sides(c.mu20, c.mu11, c.mu02, &r.long_px, &r.short_px);
    r.area_px = c.area_px;
    r.dark_px = c.dark_px;
    r.fill = fill;
    r.touches_border = c.touches_border;
  }
  return count;
}

}  // namespace ceilpose
