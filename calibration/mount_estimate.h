#pragma once
// Where the camera sits on the robot (SPEC §10 `calibrate mount`, and the
// mount of `calibrate robot`), from the camera's own poses over a drive.
//
// A turn in place is the camera running on a circle around a *still* centre
// (the robot's origin); expressed in the camera's own heading frame, that
// centre is the same point on every frame of every turn in place, and the
// mount offset is it, turned back by the mounting yaw. Driving straight, the
// camera moves along the robot's heading: the angle between the camera's yaw
// and its motion is the mounting yaw. Segments end at a jump, a time gap, a
// pause or a change of motion; a turning segment whose centre moves or sits
// farther than any mount could is an arc (turning while driving), not a turn
// in place; a circle that fits far worse than the localization noise is
// rejected with its figures.
#include <string>
#include <vector>

#include "core/result.h"

namespace ceilpose {

// One frame's camera pose in `map` (the optical centre's x, y and the
// camera's yaw, i.e. localized with a zero mount).
struct CameraSample {
  double t_s = 0.0;
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

struct MountEstimateOptions {
  // The farthest a camera is mounted from the robot's turning centre: a
  // circle wider than this is an arc, not a turn in place.
  double max_offset_m = 0.30;
  // Consecutive frames further apart than this in time end a segment.
  double max_gap_s = 0.5;
  // The fastest the robot moves: a step beyond it is a jump (the recording
  // paused while the robot was carried).
  double max_speed_mps = 2.0;
  // A turn in place's circle fitting worse than this (RMS of the camera's
  // distance from it) is not a turn in place around a still centre.
  double max_circle_rms_m = 0.003;
  // Results known worse than this (1-sigma) are refused (docs/commissioning.md).
  double max_sigma_offset_m = 0.001;
  double max_sigma_yaw_rad = 0.0017;        // 0.1°
  double min_turn_rad = 6.283185307179586;  // SPEC §10: 360° in total
  double min_drive_m = 1.0;                 // SPEC §10: 1 m in total
};

// A stretch of the drive as the estimate read it, for the report.
struct MotionSegment {
  enum Kind { kTurnInPlace, kArc, kRejectedTurn, kStraight, kStraightBackwards };
  Kind kind = kStraight;
  size_t first = 0, last = 0;  // sample indices, inclusive
  double turned_rad = 0.0;     // |rotation| over the segment
  double length_m = 0.0;       // straight: the distance driven
  double radius_m = 0.0;       // turning: the camera's circle
  double rms_m = 0.0;          // circle or line fit
};

struct MountEstimate {
  double offset_forward_m = 0.0, offset_left_m = 0.0, yaw_rad = 0.0;
  double sigma_forward_m = 0.0, sigma_left_m = 0.0, sigma_yaw_rad = 0.0;
  double turned_rad = 0.0;   // total turning in place used
  double driven_m = 0.0;     // total straight drive used
  double backwards_m = 0.0;  // of which driven backwards
  int turn_segments = 0, straight_segments = 0;
  double circle_rms_m = 0.0;            // how well the turning camera fits its circles
  double line_rms_m = 0.0;              // how well the driving camera fits its lines
  std::vector<MotionSegment> segments;  // every segment found, used or not
};

const char* to_string(MotionSegment::Kind kind);

// Refuses, saying what is missing or what did not fit, without 360° of
// turning in place and 1 m of straight drive in total (SPEC §10), when the
// turns in place disagree about where the robot's centre is, or when the
// result is known worse than the options' sigmas.
Result<MountEstimate> estimate_mount(const std::vector<CameraSample>& samples,
                                     const MountEstimateOptions& options = {});

}  // namespace ceilpose
