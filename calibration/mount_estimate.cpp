#include "calibration/mount_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/pose.h"
#include "core/units.h"

namespace ceilpose {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTurningRadps = 0.15;   // faster than this: turning
constexpr double kStraightRadps = 0.02;  // slower than this and moving: straight
constexpr double kMovingMps = 0.05;
constexpr double kStraightWindowS = 0.3;
constexpr size_t kMinSegmentFrames = 5;
// A turning step's rotation centre further than this (or half the circle's
// radius) from the segment's: the centre moved, the segment ends.
constexpr double kCentreMoveM = 0.03;
constexpr double kStepNoiseM = 0.002;
// Turns in place agree on the robot's centre (in the camera's frame) within
// this, or the ones that disagree are arcs.
constexpr double kCentreAgreeM = 0.01;
// A straight step turning its direction more than this from the segment's
// ends it.
constexpr double kStraightBendRad = 10.0 * kRadPerDeg;

enum class StepKind { kBroken, kOther, kTurning, kStraight };

struct Step {
  StepKind kind = StepKind::kBroken;
  double dtheta_rad = 0.0;
  double cx_m = 0.0, cy_m = 0.0;  // turning: the rotation's fixed point
  double direction_rad = 0.0;     // straight: of the motion
};

std::vector<Step> steps_of(const std::vector<CameraSample>& s, const MountEstimateOptions& o) {
  std::vector<Step> steps(s.size() > 0 ? s.size() - 1 : 0);
  for (size_t k = 0; k + 1 < s.size(); ++k) {
    Step& st = steps[k];
    const double dt = s[k + 1].t_s - s[k].t_s;
    const double dx = s[k + 1].x_m - s[k].x_m, dy = s[k + 1].y_m - s[k].y_m;
    const double dist = std::hypot(dx, dy);
    if (!(dt > 0.0) || dt > o.max_gap_s || dist / dt > o.max_speed_mps) continue;  // broken
    st.dtheta_rad = wrap_angle_rad(s[k + 1].yaw_rad - s[k].yaw_rad);
    const double rate = std::abs(st.dtheta_rad) / dt;
    // Whether it drives straight is judged over kStraightWindowS: one
    // step's yaw noise (0.02° at 30 fps is 0.015 rad/s) would break
    // straight runs into fragments.
    size_t a = k, b = k + 1;
    while (s[b].t_s - s[a].t_s < kStraightWindowS && (a > 0 || b + 1 < s.size())) {
      if (a > 0) --a;
      if (b + 1 < s.size()) ++b;
    }
    double turned = 0.0;
    for (size_t i = a; i < b; ++i) turned += wrap_angle_rad(s[i + 1].yaw_rad - s[i].yaw_rad);
    const double window_rate = std::abs(turned) / (s[b].t_s - s[a].t_s);
    if (rate > kTurningRadps) {
      // The fixed point c of the rigid motion: p1 − c = R(Δθ)(p0 − c).
      const double c = std::cos(st.dtheta_rad), sn = std::sin(st.dtheta_rad);
      const double bx = s[k + 1].x_m - (c * s[k].x_m - sn * s[k].y_m);
      const double by = s[k + 1].y_m - (sn * s[k].x_m + c * s[k].y_m);
      // (I − R) = [[1 − c, sn], [−sn, 1 − c]], determinant 2 − 2c.
      const double det = 2.0 - 2.0 * c;
      st.cx_m = ((1.0 - c) * bx - sn * by) / det;
      st.cy_m = (sn * bx + (1.0 - c) * by) / det;
      st.kind = StepKind::kTurning;
    } else if (window_rate < kStraightRadps && dist / dt > kMovingMps) {
      st.direction_rad = std::atan2(dy, dx);
      st.kind = StepKind::kStraight;
    } else {
      st.kind = StepKind::kOther;
    }
  }
  return steps;
}

// Least-squares circle (Kåsa) through samples [first, last]: centre, radius.
void fit_circle(const std::vector<CameraSample>& s, size_t first, size_t last, double* cx,
                double* cy, double* r) {
  double mx = 0.0, my = 0.0;
  const double n = static_cast<double>(last - first + 1);
  for (size_t k = first; k <= last; ++k) {
    mx += s[k].x_m / n;
    my += s[k].y_m / n;
  }
  double suu = 0, svv = 0, suv = 0, suuu = 0, svvv = 0, suvv = 0, svuu = 0;
  for (size_t k = first; k <= last; ++k) {
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

// A turn in place read from the frames: the robot's centre in each frame's
// camera heading frame, b_k = R(−θ_k)(c − p_k).
struct Turn {
  MotionSegment segment;
  double bx_m = 0.0, by_m = 0.0;  // mean over the frames
  size_t frames = 0;
};

std::vector<Turn> turning_segments(const std::vector<CameraSample>& s,
                                   const std::vector<Step>& steps, const MountEstimateOptions& o,
                                   std::vector<MotionSegment>* report) {
  std::vector<Turn> turns;
  size_t k = 0;
  while (k < steps.size()) {
    if (steps[k].kind != StepKind::kTurning) {
      ++k;
      continue;
    }
    // Grow the run while each step turns about the run's centre.
    double sx = steps[k].cx_m, sy = steps[k].cy_m;
    size_t e = k + 1;
    while (e < steps.size() && steps[e].kind == StepKind::kTurning &&
           (steps[e].dtheta_rad > 0) == (steps[k].dtheta_rad > 0)) {
      const double n = static_cast<double>(e - k);
      const double mx = sx / n, my = sy / n;
      const double radius = std::hypot(mx - s[e].x_m, my - s[e].y_m);
      // The fixed point of a small rotation is uncertain by about the
      // position noise over the angle: kStepNoiseM / |Δθ| keeps noise from
      // splitting a slow turn.
      if (std::hypot(steps[e].cx_m - mx, steps[e].cy_m - my) >
          std::max({kCentreMoveM, 0.5 * radius, kStepNoiseM / std::abs(steps[e].dtheta_rad)}))
        break;
      sx += steps[e].cx_m;
      sy += steps[e].cy_m;
      ++e;
    }
    const size_t first = k, last = e;  // samples first..last
    k = e;
    if (last - first + 1 < kMinSegmentFrames) continue;
    MotionSegment seg;
    seg.first = first;
    seg.last = last;
    for (size_t i = first; i < last; ++i) seg.turned_rad += std::abs(steps[i].dtheta_rad);
    double cx = 0.0, cy = 0.0;
    fit_circle(s, first, last, &cx, &cy, &seg.radius_m);
    double sq = 0.0;
    Turn t;
    for (size_t i = first; i <= last; ++i) {
      const double dx = cx - s[i].x_m, dy = cy - s[i].y_m;
      sq += std::pow(std::hypot(dx, dy) - seg.radius_m, 2);
      const double c = std::cos(s[i].yaw_rad), sn = std::sin(s[i].yaw_rad);
      t.bx_m += c * dx + sn * dy;
      t.by_m += -sn * dx + c * dy;
    }
    t.frames = last - first + 1;
    t.bx_m /= static_cast<double>(t.frames);
    t.by_m /= static_cast<double>(t.frames);
    seg.rms_m = std::sqrt(sq / static_cast<double>(t.frames));
    if (seg.radius_m > o.max_offset_m) {
      seg.kind = MotionSegment::kArc;
    } else if (seg.rms_m > o.max_circle_rms_m) {
      seg.kind = MotionSegment::kRejectedTurn;
    } else {
      seg.kind = MotionSegment::kTurnInPlace;
      t.segment = seg;
      turns.push_back(t);
    }
    report->push_back(seg);
  }
  return turns;
}

struct Straight {
  MotionSegment segment;
  double gamma_rad = 0.0;  // camera yaw minus the robot's heading
  size_t frames = 0;
};

std::vector<Straight> straight_segments(const std::vector<CameraSample>& s,
                                        const std::vector<Step>& steps,
                                        std::vector<MotionSegment>* report, double* line_sq,
                                        int* line_n) {
  std::vector<Straight> out;
  size_t k = 0;
  while (k < steps.size()) {
    if (steps[k].kind != StepKind::kStraight) {
      ++k;
      continue;
    }
    size_t e = k + 1;
    while (e < steps.size() && steps[e].kind == StepKind::kStraight &&
           std::abs(wrap_angle_rad(steps[e].direction_rad - steps[k].direction_rad)) <
               kStraightBendRad)
      ++e;
    const size_t first = k, last = e;
    k = e;
    if (last - first + 1 < kMinSegmentFrames) continue;
    const CameraSample& a = s[first];
    const CameraSample& b = s[last];
    Straight st;
    st.frames = last - first + 1;
    st.segment.first = first;
    st.segment.last = last;
    st.segment.length_m = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    const double direction = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
    double ys = 0.0, yc = 0.0, sq = 0.0;
    for (size_t i = first; i <= last; ++i) {
      ys += std::sin(s[i].yaw_rad);
      yc += std::cos(s[i].yaw_rad);
      const double off =
          -(s[i].x_m - a.x_m) * std::sin(direction) + (s[i].y_m - a.y_m) * std::cos(direction);
      sq += off * off;
    }
    *line_sq += sq;
    *line_n += static_cast<int>(st.frames);
    st.segment.rms_m = std::sqrt(sq / static_cast<double>(st.frames));
    st.gamma_rad = wrap_angle_rad(std::atan2(ys, yc) - direction);
    // SPEC §3: the image top faces the robot's forward axis, so a mounting
    // yaw is a correction well inside ±90°: a camera whose image top points
    // against its motion is on a robot driving backwards.
    st.segment.kind = MotionSegment::kStraight;
    if (std::abs(st.gamma_rad) > 0.5 * kPi) {
      st.gamma_rad = wrap_angle_rad(st.gamma_rad - kPi);
      st.segment.kind = MotionSegment::kStraightBackwards;
    }
    report->push_back(st.segment);
    out.push_back(st);
  }
  return out;
}

std::string figure(const char* format, double value) {
  char t[64];
  std::snprintf(t, sizeof t, format, value);
  return t;
}

std::string rejected_turns(const std::vector<MotionSegment>& segments) {
  int arcs = 0, rejected = 0;
  double worst_rms = 0.0;
  for (const MotionSegment& g : segments) {
    if (g.kind == MotionSegment::kArc) ++arcs;
    if (g.kind == MotionSegment::kRejectedTurn) {
      ++rejected;
      worst_rms = std::max(worst_rms, g.rms_m);
    }
  }
  std::string out;
  if (arcs > 0)
    out += std::to_string(arcs) + " turning segment(s) were arcs (turning while driving)";
  if (rejected > 0)
    out += std::string(out.empty() ? "" : ", ") + std::to_string(rejected) +
           " turned about a moving centre (circle RMS up to " + figure("%.1f", 1000.0 * worst_rms) +
           " mm)";
  return out.empty() ? "" : " (" + out + ")";
}

}  // namespace

const char* to_string(MotionSegment::Kind kind) {
  switch (kind) {
    case MotionSegment::kTurnInPlace:
      return "turn in place";
    case MotionSegment::kArc:
      return "arc (not used)";
    case MotionSegment::kRejectedTurn:
      return "turn about a moving centre (not used)";
    case MotionSegment::kStraight:
      return "straight";
    case MotionSegment::kStraightBackwards:
      return "straight, backwards";
  }
  return "?";
}

Result<MountEstimate> estimate_mount(const std::vector<CameraSample>& samples,
                                     const MountEstimateOptions& options) {
  MountEstimate m;
  const std::vector<Step> steps = steps_of(samples, options);
  std::vector<Turn> turns = turning_segments(samples, steps, options, &m.segments);
  double line_sq = 0.0;
  int line_n = 0;
  const std::vector<Straight> straights =
      straight_segments(samples, steps, &m.segments, &line_sq, &line_n);
  std::sort(m.segments.begin(), m.segments.end(),
            [](const MotionSegment& a, const MotionSegment& b) { return a.first < b.first; });

  // The turns in place agree on where the robot's centre is; a turn whose
  // centre disagrees with the most turning is an arc of small radius.
  size_t best = 0;
  double best_turned = -1.0;
  for (size_t i = 0; i < turns.size(); ++i) {
    double agreeing = 0.0;
    for (const Turn& t : turns)
      if (std::hypot(t.bx_m - turns[i].bx_m, t.by_m - turns[i].by_m) < kCentreAgreeM)
        agreeing += t.segment.turned_rad;
    if (agreeing > best_turned) {
      best_turned = agreeing;
      best = i;
    }
  }
  double bx = 0.0, by = 0.0, circle_sq = 0.0;
  size_t frames = 0;
  std::vector<Turn> used;
  for (const Turn& t : turns) {
    const bool agrees =
        std::hypot(t.bx_m - turns[best].bx_m, t.by_m - turns[best].by_m) < kCentreAgreeM;
    for (MotionSegment& g : m.segments)
      if (g.first == t.segment.first && g.kind == MotionSegment::kTurnInPlace && !agrees)
        g.kind = MotionSegment::kArc;
    if (!agrees) continue;
    used.push_back(t);
    bx += t.bx_m * static_cast<double>(t.frames);
    by += t.by_m * static_cast<double>(t.frames);
    frames += t.frames;
    circle_sq += t.segment.rms_m * t.segment.rms_m * static_cast<double>(t.frames);
    m.turned_rad += t.segment.turned_rad;
    ++m.turn_segments;
  }
  double sin_sum = 0.0, cos_sum = 0.0;
  for (const Straight& st : straights) {
    sin_sum += st.segment.length_m * std::sin(st.gamma_rad);
    cos_sum += st.segment.length_m * std::cos(st.gamma_rad);
    m.driven_m += st.segment.length_m;
    if (st.segment.kind == MotionSegment::kStraightBackwards) m.backwards_m += st.segment.length_m;
    ++m.straight_segments;
  }
  if (m.turned_rad < options.min_turn_rad || m.driven_m < options.min_drive_m) {
    std::string missing;
    if (m.turned_rad < options.min_turn_rad)
      missing += "turning in place: " + figure("%.0f", m.turned_rad * kDegPerRad) + " deg found" +
                 rejected_turns(m.segments) + ", " +
                 figure("%.0f", options.min_turn_rad * kDegPerRad) + " needed";
    if (m.driven_m < options.min_drive_m)
      missing += (missing.empty() ? "" : "; ") + std::string("straight drive: ") +
                 figure("%.2f", m.driven_m) + " m found, " + figure("%.2f", options.min_drive_m) +
                 " m needed";
    return make_error("the recording lacks " + missing +
                      " (turn the robot in place a full turn and drive it straight ahead)");
  }
  m.yaw_rad = std::atan2(sin_sum, cos_sum);
  bx /= static_cast<double>(frames);
  by /= static_cast<double>(frames);
  // b = −R(−γ)·o, so o = −R(γ)·b.
  const double cg = std::cos(m.yaw_rad), sg = std::sin(m.yaw_rad);
  m.offset_forward_m = -(cg * bx - sg * by);
  m.offset_left_m = -(sg * bx + cg * by);
  m.circle_rms_m = std::sqrt(circle_sq / static_cast<double>(frames));
  m.line_rms_m = std::sqrt(line_sq / std::max(1, line_n));

  // Sigmas: the centre of a circle fitted to N points of RMS r is known to
  // about r·√(2/N); several turns in place also show their scatter.
  double var_b = m.circle_rms_m * m.circle_rms_m * 2.0 / static_cast<double>(frames);
  if (used.size() >= 2) {
    double scatter = 0.0;
    for (const Turn& t : used) scatter += std::pow(t.bx_m - bx, 2) + std::pow(t.by_m - by, 2);
    var_b = std::max(var_b, 0.5 * scatter / static_cast<double>((used.size() - 1) * used.size()));
  }
  double yaw_var = 0.0;
  if (straights.size() >= 2) {
    for (const Straight& st : straights)
      yaw_var += std::pow(wrap_angle_rad(st.gamma_rad - m.yaw_rad), 2);
    yaw_var /= static_cast<double>((straights.size() - 1) * straights.size());
  }
  yaw_var = std::max(yaw_var, std::pow(m.line_rms_m / m.driven_m, 2) * 12.0 / std::max(1, line_n));
  m.sigma_yaw_rad = std::sqrt(yaw_var);
  const double r = std::hypot(bx, by);
  m.sigma_forward_m = std::sqrt(var_b + std::pow(r * m.sigma_yaw_rad, 2));
  m.sigma_left_m = m.sigma_forward_m;
  if (m.sigma_forward_m > options.max_sigma_offset_m || m.sigma_yaw_rad > options.max_sigma_yaw_rad)
    return make_error("the drive does not determine the mount well enough: offset 1-sigma " +
                      figure("%.2f", 1000.0 * m.sigma_forward_m) + " mm (limit " +
                      figure("%.2f", 1000.0 * options.max_sigma_offset_m) + " mm), yaw 1-sigma " +
                      figure("%.3f", m.sigma_yaw_rad * kDegPerRad) + " deg (limit " +
                      figure("%.3f", options.max_sigma_yaw_rad * kDegPerRad) +
                      " deg); circle RMS " + figure("%.2f", 1000.0 * m.circle_rms_m) + " mm over " +
                      std::to_string(used.size()) + " turn(s) in place, " +
                      std::to_string(straights.size()) +
                      " straight drive(s): turn more, drive straighter and longer");
  return m;
}

}  // namespace ceilpose
