#include "calibration/mount_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/pose.h"

namespace ceilpose {
namespace {

constexpr double kTurningRadps = 0.15;   // faster than this: turning
constexpr double kStraightRadps = 0.02;  // slower than this and moving: straight
constexpr double kMovingMps = 0.05;
constexpr size_t kMinSegment = 5;  // frames

struct Segment {
  size_t begin, end;  // [begin, end) into the samples
  bool turning;
};

std::vector<Segment> segments(const std::vector<CameraSample>& s) {
  std::vector<Segment> out;
  auto kind = [&](size_t k) {  // 0 other, 1 turning, 2 straight, at step k -> k + 1
    const double dt = s[k + 1].t_s - s[k].t_s;
    if (!(dt > 0.0)) return 0;
    const double rate = std::abs(wrap_angle_rad(s[k + 1].yaw_rad - s[k].yaw_rad)) / dt;
    const double speed = std::hypot(s[k + 1].x_m - s[k].x_m, s[k + 1].y_m - s[k].y_m) / dt;
    if (rate > kTurningRadps) return 1;
    if (rate < kStraightRadps && speed > kMovingMps) return 2;
    return 0;
  };
  size_t k = 0;
  while (k + 1 < s.size()) {
    const int c = kind(k);
    size_t e = k + 1;
    while (e + 1 < s.size() && kind(e) == c) ++e;
    if (c != 0 && e + 1 - k >= kMinSegment) out.push_back({k, e + 1, c == 1});
    k = e;
  }
  return out;
}

// Least-squares circle (Kåsa): centre and radius.
void fit_circle(const std::vector<CameraSample>& s, const Segment& g, double* cx, double* cy,
                double* r) {
  double mx = 0.0, my = 0.0;
  const double n = static_cast<double>(g.end - g.begin);
  for (size_t k = g.begin; k < g.end; ++k) {
    mx += s[k].x_m / n;
    my += s[k].y_m / n;
  }
  double suu = 0, svv = 0, suv = 0, suuu = 0, svvv = 0, suvv = 0, svuu = 0;
  for (size_t k = g.begin; k < g.end; ++k) {
    const double u = s[k].x_m - mx, v = s[k].y_m - my;
    suu += u * u;
    svv += v * v;
    suv += u * v;
    suuu += u * u * u;
    svvv += v * v * v;
    suvv += u * v * v;
    svuu += v * u * u;
  }
  const double b1 = 0.5 * (suuu + suvv), b2 = 0.5 * (svvv + svuu);
  const double det = suu * svv - suv * suv;
  double uc = 0.0, vc = 0.0;
  if (std::abs(det) > 1e-18) {
    uc = (b1 * svv - b2 * suv) / det;
    vc = (suu * b2 - suv * b1) / det;
  }
  *cx = mx + uc;
  *cy = my + vc;
  *r = std::sqrt(uc * uc + vc * vc + (suu + svv) / n);
}

std::string degrees(double rad) {
  char t[32];
  std::snprintf(t, sizeof t, "%.0f", rad * 180.0 / std::numbers::pi);
  return t;
}

}  // namespace

Result<MountEstimate> estimate_mount(const std::vector<CameraSample>& samples) {
  MountEstimate m;
  const std::vector<Segment> parts = segments(samples);
  // Mounting yaw from the straight drives: the camera's yaw minus the
  // direction it moves in, weighted by the distance driven.
  double sin_sum = 0.0, cos_sum = 0.0, line_sq = 0.0;
  int line_n = 0;
  std::vector<double> yaw_per_segment;
  for (const Segment& g : parts) {
    if (g.turning) continue;
    const CameraSample& a = samples[g.begin];
    const CameraSample& b = samples[g.end - 1];
    const double length = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    const double direction = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
    double ys = 0.0, yc = 0.0;
    for (size_t k = g.begin; k < g.end; ++k) {
      ys += std::sin(samples[k].yaw_rad);
      yc += std::cos(samples[k].yaw_rad);
      const double dx = samples[k].x_m - a.x_m, dy = samples[k].y_m - a.y_m;
      const double off = -dx * std::sin(direction) + dy * std::cos(direction);
      line_sq += off * off;
      ++line_n;
    }
    const double gamma = wrap_angle_rad(std::atan2(ys, yc) - direction);
    sin_sum += length * std::sin(gamma);
    cos_sum += length * std::cos(gamma);
    yaw_per_segment.push_back(gamma);
    m.driven_m += length;
    ++m.straight_segments;
  }
  // Offset from the turns in place: radius and phase of the camera's circle.
  double turned = 0.0, circle_sq = 0.0;
  int circle_n = 0;
  double r_sum = 0.0, phase_s = 0.0, phase_c = 0.0;
  std::vector<double> radius_per_segment, phase_samples;
  for (const Segment& g : parts) {
    if (!g.turning) continue;
    double turn = 0.0;
    for (size_t k = g.begin + 1; k < g.end; ++k)
      turn += std::abs(wrap_angle_rad(samples[k].yaw_rad - samples[k - 1].yaw_rad));
    double cx = 0.0, cy = 0.0, r = 0.0;
    fit_circle(samples, g, &cx, &cy, &r);
    for (size_t k = g.begin; k < g.end; ++k) {
      const double dx = samples[k].x_m - cx, dy = samples[k].y_m - cy;
      const double d = std::hypot(dx, dy) - r;
      circle_sq += d * d;
      ++circle_n;
      // The camera sits at angle θ + atan2(l, f) from the robot origin, with
      // θ = ψ − γ: this phase minus ψ is atan2(l, f) − γ.
      const double phase = wrap_angle_rad(std::atan2(dy, dx) - samples[k].yaw_rad);
      phase_s += std::sin(phase);
      phase_c += std::cos(phase);
      phase_samples.push_back(phase);
    }
    r_sum += r * turn;
    radius_per_segment.push_back(r);
    turned += turn;
    ++m.turn_segments;
  }
  m.turned_rad = turned;
  if (turned < 2.0 * std::numbers::pi || m.driven_m < 1.0) {
    std::string missing;
    if (turned < 2.0 * std::numbers::pi)
      missing += "turning in place: " + degrees(turned) + " deg found, 360 needed";
    if (m.driven_m < 1.0) {
      char t[96];
      std::snprintf(t, sizeof t, "straight forward drive: %.2f m found, 1 m needed", m.driven_m);
      missing += (missing.empty() ? "" : "; ") + std::string(t);
    }
    return make_error("the recording lacks " + missing +
                      " (turn the robot in place a full turn and drive it straight ahead)");
  }
  m.yaw_rad = std::atan2(sin_sum, cos_sum);
  const double r = r_sum / turned;
  const double phase = std::atan2(phase_s, phase_c);
  const double angle = phase + m.yaw_rad;
  m.offset_forward_m = r * std::cos(angle);
  m.offset_left_m = r * std::sin(angle);
  m.circle_rms_m = std::sqrt(circle_sq / std::max(1, circle_n));
  m.line_rms_m = std::sqrt(line_sq / std::max(1, line_n));
  // Uncertainty from the scatter: the circle's radial residuals over the
  // samples, the phases' spread, the segments' yaw spread (or, from one
  // segment, its lateral residual over its length).
  double phase_var = 0.0;
  for (double p : phase_samples) phase_var += std::pow(wrap_angle_rad(p - phase), 2);
  phase_var /= std::max<size_t>(1, phase_samples.size() - 1) * phase_samples.size();
  double yaw_var = 0.0;
  if (yaw_per_segment.size() >= 2) {
    for (double g : yaw_per_segment) yaw_var += std::pow(wrap_angle_rad(g - m.yaw_rad), 2);
    yaw_var /= (yaw_per_segment.size() - 1) * yaw_per_segment.size();
  } else {
    yaw_var = std::pow(m.line_rms_m / m.driven_m, 2) * 12.0 / std::max(1, line_n);
  }
  const double r_var = m.circle_rms_m * m.circle_rms_m / std::max(1, circle_n);
  m.sigma_yaw_rad = std::sqrt(yaw_var);
  const double angle_var = phase_var + yaw_var;
  m.sigma_forward_m = std::sqrt(r_var * std::pow(std::cos(angle), 2) +
                                r * r * angle_var * std::pow(std::sin(angle), 2));
  m.sigma_left_m = std::sqrt(r_var * std::pow(std::sin(angle), 2) +
                             r * r * angle_var * std::pow(std::cos(angle), 2));
  return m;
}

}  // namespace ceilpose
