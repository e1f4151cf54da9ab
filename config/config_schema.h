#pragma once
// The one list of configuration keys. Reading (config_loader.cpp) and writing
// (config_writer.cpp) both walk it, so a key cannot be readable but not
// printable, or documented under a different name. Internal to config/.
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <utility>

#include "capture/source_spec.h"
#include "config/service_config.h"
#include "core/ros_name.h"
#include "ipc/shm/shm_common.h"
#include "pipeline/marker_observation.h"

namespace ceilpose::config_detail {

template <typename T>
using Choices = std::initializer_list<std::pair<const char*, T>>;

// Returns nullptr when `value` is acceptable, else what was expected.
using TextCheck = const char* (*)(const std::string& value);

inline const char* check_source(const std::string& s) {
  static const std::string expected = "a source: " + std::string(capture::kSourceSpecForms);
  return capture::parse_source_spec(s) ? nullptr : expected.c_str();
}

inline const char* check_shm_name(const std::string& s) {
  static const std::string expected = std::string("a shared-memory name: ") + shm::kShmNameRule;
  return shm::valid_shm_name(s) ? nullptr : expected.c_str();
}

// Empty: the host name, made a ROS name (daemon/service.cpp).
inline const char* check_robot_name(const std::string& s) {
  if (s.empty() || is_valid_ros_name(s)) return nullptr;
  return kRosNameRule;
}

// Looked up here, so that a group missing on this machine is a
// configuration error (exit 3), not a failure at start-up that systemd
// restarts forever.
inline const char* check_group(const std::string& s) {
  if (s.empty() || shm::lookup_group(s, "ipc", nullptr)) return nullptr;
  return "an existing group (see getent group), or empty for the daemon's own";
}

inline const char* check_any_text(const std::string&) { return nullptr; }

inline const char* check_no_space(const std::string& s) {
  if (s.find_first_of(" \t\n/") == std::string::npos) return nullptr;
  return "a name without spaces or '/'";
}

// A TF frame id: what tf2 accepts and the DDS options can carry.
inline const char* check_frame_name(const std::string& s) {
  if (s.size() > 255) return "a frame name of at most 255 characters";
  for (char ch : s) {
    if (ch == ' ' || ch == '"' || ch == '\'' || ch == '<' || ch == '>' || ch == '&' || ch == ',' ||
        static_cast<unsigned char>(ch) < 0x20)
      return "a frame name without spaces, quotes, commas or <>&";
  }
  return nullptr;
}

inline constexpr double kPi = std::numbers::pi;

// Sections SIGHUP applies live (is_live_key), and the keys in them that
// still need a restart: the image size fixes buffers and the capture format.
// with_live_keys() (config_writer.cpp) copies exactly these; a test checks
// that for every key.
inline constexpr std::array<const char*, 7> kLiveSections{
    "camera", "mount", "ceiling", "detector", "positioning", "filter", "logging"};
inline constexpr std::array<const char*, 2> kRestartKeys{"camera.width", "camera.height"};

// Visitor V provides:
//   section(name, fn)             a nested mapping
//   field(name, int&/float&/double&/uint64_t&, min, max)
//   field(name, bool&)
//   text(name, std::string&, TextCheck)
//   texts(name, std::vector<std::string>&, TextCheck)
//   choice(name, T&, Choices<T>)
//   numbers(name, std::array<double, N>&)
//   colour(name, Rgb&)
template <typename V>
void describe(V& v, ServiceConfig& c) {
  PipelineConfig& p = c.pipeline;
  v.section("camera", [&] {
    CameraIntrinsics& k = p.intrinsics;
    namespace key = camera_keys;
    v.field(key::kWidth, k.width, 1, kMaxImageSidePx);
    v.field(key::kHeight, k.height, 1, kMaxImageSidePx);
    v.field(key::kFx, k.fx, 1.0, 1e6);
    v.field(key::kFy, k.fy, 1.0, 1e6);
    v.field(key::kCx, k.cx, -1e5, 1e5);
    v.field(key::kCy, k.cy, -1e5, 1e5);
    v.numbers(key::kDistortion, k.distortion);
    v.field(key::kReadoutMs, k.readout_ms, 0.0, kMaxReadoutMs);
    v.text("calibration_file", c.calibration.camera_file, check_any_text);
  });
  v.section("mount", [&] {
    CameraMount& m = p.mount;
    v.field("lens_height_m", m.lens_height_m, 0.0, 10.0);
    v.field("offset_forward_m", m.offset_forward_m, -10.0, 10.0);
    v.field("offset_left_m", m.offset_left_m, -10.0, 10.0);
    v.field("yaw_rad", m.yaw_rad, -kPi, kPi);
    v.field("tilt_x_rad", m.tilt_x_rad, -0.35, 0.35);
    v.field("tilt_y_rad", m.tilt_y_rad, -0.35, 0.35);
  });
  v.section("ceiling", [&] {
    CeilingLayout& l = p.layout;
    v.field("height_m", l.height_m, 0.1, 100.0);
    v.field("grid_m", l.grid_m, 0.01, 100.0);
    v.field("bits", l.bits, 1, kMaxBits);
    v.field("rect_width_m", l.rect_width_m, 0.001, 10.0);
    v.field("rect_height_m", l.rect_height_m, 0.001, 10.0);
    v.field("slot_pitch_m", l.slot_pitch_m, 0.001, 10.0);
    v.field("green_dot_e_m", l.green_dot_e_m, 0.001, 10.0);
    v.field("green_dot_n_m", l.green_dot_n_m, 0.001, 10.0);
    v.field("red_dot_e_m", l.red_dot_e_m, 0.001, 10.0);
    v.field("red_dot_n_m", l.red_dot_n_m, 0.001, 10.0);
    v.field("rail_width_m", l.rail_width_m, 0.0, 1.0);
    v.colour("red", l.red);
    v.colour("green", l.green);
    v.colour("dot", l.dot);
    v.colour("tile", l.tile);
    v.colour("rail", l.rail);
    v.text("map", c.calibration.map_file, check_any_text);
  });
  v.section("detector", [&] {
    DetectorParams& d = p.detector;
    v.field("dark_max_value", d.dark_max_value, 0, 255);
    v.field("red_min_saturation", d.red_min_saturation, 0.0f, 1.0f);
    v.field("green_min_saturation", d.green_min_saturation, 0.0f, 1.0f);
    v.field("red_green_split", d.red_green_split, -255, 255);
    v.field("red_hue_min_deg", d.red_hue_min_deg, -180.0f, 360.0f);
    v.field("red_hue_max_deg", d.red_hue_max_deg, -180.0f, 360.0f);
    v.field("green_hue_min_deg", d.green_hue_min_deg, -180.0f, 360.0f);
    v.field("green_hue_max_deg", d.green_hue_max_deg, -180.0f, 360.0f);
    v.field("white_sample_step_px", d.white_sample_step_px, 1, 256);
    v.field("white_min_share", d.white_min_share, 0.0f, 1.0f);
    v.field("max_runs_per_pixel", d.max_runs_per_pixel, 0.001f, 1.0f);
    v.field("min_rect_area_px", d.min_rect_area_px, 1, 1 << 24);
    v.field("area_min_ratio", d.area_min_ratio, 0.0f, 100.0f);
    v.field("area_max_ratio", d.area_max_ratio, 0.0f, 100.0f);
    v.field("aspect_min", d.aspect_min, 0.0f, 1.0f);
    v.field("aspect_max", d.aspect_max, 0.0f, 1.0f);
    v.field("fill_min", d.fill_min, 0.0f, 2.0f);
    v.field("fill_max", d.fill_max, 0.0f, 2.0f);
    v.field("pair_distance_tolerance", d.pair_distance_tolerance, 0.0f, 10.0f);
    v.field("pair_area_tolerance", d.pair_area_tolerance, 0.0f, 10.0f);
    v.field("pair_length_tolerance", d.pair_length_tolerance, 0.0f, 10.0f);
    v.field("pair_angle_tolerance_rad", d.pair_angle_tolerance_rad, 0.0f, 3.15f);
    v.field("dot_threshold_ratio", d.dot_threshold_ratio, 0.0f, 1.0f);
    v.field("dot_search_m", d.dot_search_m, 0.0, 1.0);
    v.field("dot_min_margin", d.dot_min_margin, 0.0f, 1.0f);
    v.field("dot_threshold_blur_shift", d.dot_threshold_blur_shift, 0.0f, 1.0f);
    v.field("blur_shift_start", d.blur_shift_start, 0.0f, 100.0f);
    v.field("blur_shift_full", d.blur_shift_full, 0.0f, 100.0f);
    v.field("sampling_blur_px", d.sampling_blur_px, 0.0f, 100.0f);
    v.field("max_blur_to_dot", d.max_blur_to_dot, 0.0f, 100.0f);
    v.field("quality_full_margin", d.quality_full_margin, 0.001f, 1.0f);
    v.field("quality_zero_pair_score", d.quality_zero_pair_score, 0.001f, 100.0f);
    v.field("tracking", d.tracking);
    v.field("track_edges", d.track_edges);
    v.field("halve_whole_sweeps", d.halve_whole_sweeps);
    v.field("full_sweep_every", d.full_sweep_every, 1, 1000000);
    v.field("track_margin_px", d.track_margin_px, 0.0f, 1000.0f);
    v.field("track_margin_errors", d.track_margin_errors, 0.0f, 100.0f);
    v.field("track_max_area_share", d.track_max_area_share, 0.0f, 1.0f);
  });
  v.section("positioning", [&] {
    v.choice(
        "mode", p.positioning.mode,
        Choices<PositioningMode>{
            {to_string(PositioningMode::kAuto).data(), PositioningMode::kAuto},
            {to_string(PositioningMode::kChangeOfAxes).data(), PositioningMode::kChangeOfAxes},
            {to_string(PositioningMode::kBarycentric).data(), PositioningMode::kBarycentric},
            {to_string(PositioningMode::kLeastSquares).data(), PositioningMode::kLeastSquares}});
    PositioningParams& q = p.positioning;
    v.field("lsq_max_iterations", q.lsq_max_iterations, 1, 1000);
    v.field("lsq_step_tolerance", q.lsq_step_tolerance, 0.0, 1.0);
    v.field("lsq_huber_px", q.lsq_huber_px, 0.01, 1000.0);
    v.field("lsq_marker_reject_px", q.lsq_marker_reject_px, 0.01, 1000.0);
    v.field("lsq_max_rms_px", q.lsq_max_rms_px, 0.01, 1000.0);
    v.field("lsq_min_points", q.lsq_min_points, 3, 10000);
    v.field("lsq_edge_points", q.lsq_edge_points);
    v.field("lsq_estimate_tilt", q.lsq_estimate_tilt);
    v.field("lsq_tilt_select_chi2", q.lsq_tilt_select_chi2, 0.0, 1e6);
    v.field("lsq_tilt_select_shift_sigmas", q.lsq_tilt_select_shift_sigmas, 0.0, 1e6);
    v.field("lsq_tilt_prior_rad", q.lsq_tilt_prior_rad, 1e-6, 1.0);
    v.field("lsq_max_tilt_rad", q.lsq_max_tilt_rad, 0.0, kPi / 2);
    v.field("lsq_tilt_min_markers", q.lsq_tilt_min_markers, 1, kMaxMarkersPerFrame);
    v.field("lsq_estimate_height", q.lsq_estimate_height);
    v.field("lsq_max_rejections", q.lsq_max_rejections, 0, kMaxMarkersPerFrame);
    v.field("lsq_motion_min_row_span", q.lsq_motion_min_row_span, 0.0, 1.0);
    v.field("lsq_motion_min_markers", q.lsq_motion_min_markers, 1, kMaxMarkersPerFrame);
    v.field("lsq_motion_prior_mps", q.lsq_motion_prior_mps, 1e-6, 100.0);
    v.field("lsq_motion_prior_radps", q.lsq_motion_prior_radps, 1e-6, 100.0);
    v.field("lsq_motion_prior_floor_mps", q.lsq_motion_prior_floor_mps, 0.0, 100.0);
    v.field("lsq_motion_prior_floor_radps", q.lsq_motion_prior_floor_radps, 0.0, 100.0);
    v.field("grid_tolerance_units", q.grid_tolerance_units, 0.01, 0.5);
    v.field("heading_tolerance_rad", q.heading_tolerance_rad, 0.0, kPi);
    v.field("max_depth_scale_error", q.max_depth_scale_error, 0.0, 1.0);
    v.field("barycentric_min_area_units2", q.barycentric_min_area_units2, 0.0, 100.0);
    v.field("thesis_sigma_m", q.thesis_sigma_m, 1e-6, 10.0);
    v.field("thesis_sigma_yaw_rad", q.thesis_sigma_yaw_rad, 1e-6, kPi);
    v.field("lsq_sigma_floor_m", q.lsq_sigma_floor_m, 0.0, 10.0);
    v.field("lsq_sigma_floor_yaw_rad", q.lsq_sigma_floor_yaw_rad, 0.0, kPi);
  });
  v.section("filter", [&] {
    FilterParams& f = p.filter;
    v.field("enabled", f.enabled);
    v.field("jerk_sigma_mps3", f.jerk_sigma_mps3, 1e-6, 10000.0);
    v.field("yaw_jerk_sigma_radps3", f.yaw_jerk_sigma_radps3, 1e-6, 10000.0);
    v.field("meas_sigma_floor_m", f.meas_sigma_floor_m, 0.0, 10.0);
    v.field("meas_sigma_floor_yaw_rad", f.meas_sigma_floor_yaw_rad, 0.0, kPi);
    v.field("gate_chi2", f.gate_chi2, 0.1, 1e6);
    v.field("gate_min_m", f.gate_min_m, 0.0, 100.0);
    v.field("gate_min_rad", f.gate_min_rad, 0.0, kPi);
    v.field("reinit_after_gated", f.reinit_after_gated, 1, 100000);
    v.field("min_frame_interval_ms", f.min_frame_interval_ms, 0.0, 1000.0);
    v.field("predict_timeout_ms", f.predict_timeout_ms, 0.0, 60000.0);
    v.field("coast_max_sd_m", f.coast_max_sd_m, 0.0, 1000.0);
    v.field("coast_max_yaw_sd_rad", f.coast_max_yaw_sd_rad, 0.0, 1000.0);
    v.field("init_velocity_sigma_mps", f.init_velocity_sigma_mps, 1e-6, 100.0);
    v.field("init_yaw_rate_sigma_radps", f.init_yaw_rate_sigma_radps, 1e-6, 100.0);
    v.field("init_accel_sigma_mps2", f.init_accel_sigma_mps2, 1e-6, 1000.0);
    v.field("init_yaw_accel_sigma_radps2", f.init_yaw_accel_sigma_radps2, 1e-6, 1000.0);
    v.field("predict_horizon_ms", f.predict_horizon_ms, 0.0, 10000.0);
  });
  v.section("capture", [&] {
    CaptureConfig& k = c.capture;
    capture::SourceOptions& s = k.device;
    capture::ControlLocks& locks = s.controls;
    v.text("source", k.source, &check_source);
    v.field("fps", s.fps, 0.1, 1000.0);
    using Formats = std::vector<PixelFormat>;
    v.choice("pixel_format", s.pixel_formats,
             Choices<Formats>{{"auto", capture::SourceOptions{}.pixel_formats},
                              {"yuyv", Formats{PixelFormat::kYuyv}},
                              {"nv12", Formats{PixelFormat::kNv12}},
                              {"yuv420", Formats{PixelFormat::kYuv420}},
                              {"mjpeg", Formats{PixelFormat::kMjpeg}},
                              {"rgb24", Formats{PixelFormat::kRgb24}},
                              {"bgr24", Formats{PixelFormat::kBgr24}},
                              {"gray8", Formats{PixelFormat::kGray8}}});
    v.field("buffer_count", s.buffer_count, 2, 32);
    v.field("rt_priority", k.thread.realtime_priority, 0, 99);
    v.field("cpu", k.thread.cpu, -1, 1023);
    v.field("pipeline_rt_priority", k.pipeline_rt_priority, 0, 99);
    v.field("lock_exposure", locks.lock_exposure);
    v.field("exposure_us", locks.exposure_us, 1, 10'000'000);
    v.field("lock_gain", locks.lock_gain);
    v.field("gain", locks.gain, -1, 1'000'000);
    v.field("lock_white_balance", locks.lock_white_balance);
    v.field("white_balance_k", locks.white_balance_k, 1000, 20000);
    v.field("stall_timeout_ms", s.stall_timeout_ms, 10, 600'000);
    v.field("reconnect_initial_ms", s.reconnect_initial_ms, 1, 600'000);
    v.field("reconnect_max_ms", s.reconnect_max_ms, 1, 600'000);
    v.field("replay_speed", s.replay_speed, 0.0, 1000.0);
    v.field("replay_loop", s.replay_loop);
    v.field("synthetic_seed", k.synthetic_seed, uint64_t{0}, UINT64_MAX);
  });
  v.section("ipc", [&] {
    v.text("shm_name", c.ipc.name, &check_shm_name);
    v.text("group", c.ipc.group, &check_group);
    v.field("stale_after_ms", c.ipc.stale_after_ms, 1, 600'000);
  });
  v.section("dds", [&] {
    DdsConfig& d = c.dds;
    DdsOptions& o = d.publisher;
    v.field("enabled", d.enabled);
    // RTPS port arithmetic leaves room for domains 0..230 only (Cyclone's limit).
    v.field("domain_id", o.domain.domain_id, 0u, 230u);
    v.text("robot_name", o.robot, &check_robot_name);
    v.choice("reliability", o.reliability,
             Choices<DdsReliability>{{"reliable", DdsReliability::kReliable},
                                     {"best_effort", DdsReliability::kBestEffort}});
    v.field("history_depth", o.history_depth, 1, 1000);
    v.texts("interfaces", o.domain.interfaces, &check_no_space);
    v.texts("peers", o.domain.peers, &check_no_space);
    // RTPS port arithmetic: 2 ports per index within a domain's 250.
    v.field("max_participants_per_host", o.domain.max_participants_per_host, 1u, 120u);
    v.field("status_period_ms", d.status_period_ms, 10, 60'000);
    v.section("tf", [&] {
      v.field("enabled", o.rviz.tf);
      v.text("parent_frame", o.rviz.tf_parent_frame, &check_frame_name);
      v.text("child_frame", o.rviz.tf_child_frame, &check_frame_name);
    });
    v.field("ceiling_markers", o.rviz.ceiling);
    v.section("security", [&] {
      v.text("keystore", d.security.keystore_dir, &check_any_text);
      v.text("enclave", d.security.enclave, &check_robot_name);
    });
  });
  v.section("fleet", [&] {
    FleetOptions& f = c.fleet;
    v.field("enabled", f.enabled);
    v.texts("robots", f.robots, &check_robot_name);
    v.field("capacity", f.capacity, 1u, 65536u);
    v.field("stale_after_ms", f.stale_after_ms, 10, 600'000);
    v.field("remove_after_ms", f.remove_after_ms, 10, 3'600'000);
    v.field("max_clock_offset_ms", f.max_clock_offset_ms, 0, 60'000);
    v.field("history_depth", f.history_depth, 1, 1000);
  });
  v.section("logging", [&] {
    v.choice("level", c.logging.level,
             Choices<LogLevel>{{"trace", LogLevel::kTrace},
                               {"debug", LogLevel::kDebug},
                               {"info", LogLevel::kInfo},
                               {"warn", LogLevel::kWarn},
                               {"error", LogLevel::kError},
                               {"critical", LogLevel::kCritical},
                               {"off", LogLevel::kOff}});
    v.field("problem_report_interval_ms", c.logging.problem_report_interval_ms, 100, 3'600'000);
  });
  v.section("watchdog", [&] {
    v.field("max_stall_ms", c.watchdog.max_stall_ms, 10, 600'000);
    v.field("status_interval_ms", c.watchdog.status_interval_ms, 50, 60'000);
  });
}

}  // namespace ceilpose::config_detail
