// ceilposectl calibrate camera | mount (SPEC §10): the camera's intrinsics
// from a recording of a checkerboard (OpenCV), and the camera's place on the
// robot from a recording of turns in place and straight drives.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "calibration/board_spec.h"
#include "calibration/camera_info_file.h"
#include "calibration/mount_estimate.h"
#include "calibration/mount_fragment.h"
#include "core/output_guard.h"
#include "core/units.h"
#include "ctl/calibrate_robot_command.h"
#include "ctl/calibration_options.h"
#include "ctl/command_registry.h"
#include "ctl/replay_run.h"
#include "recording/recording_reader.h"

namespace ceilpose::ctl {
namespace {

constexpr int kMinViews = 10;
// The views' corners should reach this share of a 4 x 4 grid of image cells
// and the boards tilt at least this much, or the calibration is weak.
constexpr double kMinCoverage = 0.75;
constexpr double kMinTiltDeg = 15.0;
// Progress without a terminal, and when to stop looking for a board that
// is never found.
constexpr size_t kProgressEveryFrames = 10;
constexpr size_t kGiveUpFrames = 10;

struct CameraArgs {
  std::string dir;
  std::string board = "";
  std::string out_file = "camera.yaml";
};

struct Views {
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int64_t> index;  // recording frame index of each view
  size_t frames = 0;
  bool gave_up = false;  // no board in the first kGiveUpFrames frames
};

// Finds the board in every frame: corners refined to sub-pixel.
Result<Views> find_boards(const RecordingReader& reader, const BoardSpec& board) {
  Views views;
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  const cv::Size pattern(board.cols, board.rows);
  Image image;
  for (size_t i = 0; i < reader.rows().size(); ++i) {
    if (auto loaded = reader.load_frame(i, &image); !loaded) return loaded.error();
    const ImageView v = image.view();
    // SPEC §4 allows greyscale frames: only colour ones are converted.
    cv::Mat gray;
    if (v.format == PixelFormat::kGray8) {
      gray = cv::Mat(v.height, v.width, CV_8UC1, const_cast<uint8_t*>(v.data), v.stride_bytes);
    } else {
      const cv::Mat colour(v.height, v.width, CV_8UC3, const_cast<uint8_t*>(v.data),
                           v.stride_bytes);
      cv::cvtColor(colour, gray,
                   v.format == PixelFormat::kBgr24 ? cv::COLOR_BGR2GRAY : cv::COLOR_RGB2GRAY);
    }
    std::vector<cv::Point2f> corners;
    const bool found = cv::findChessboardCorners(
        gray, pattern, corners,
        cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
    ++views.frames;
    const size_t with_board = views.corners.size() + (found ? 1 : 0);
    if (tty)
      std::fprintf(stderr, "\rcalibrate camera: frame %zu/%zu, board in %zu", i + 1,
                   reader.rows().size(), with_board);
    else if ((i + 1) % kProgressEveryFrames == 0)
      std::fprintf(stderr, "calibrate camera: frame %zu/%zu, board in %zu\n", i + 1,
                   reader.rows().size(), with_board);
    // A board of the wrong size is searched for slowly and never found:
    // say so early rather than after the whole recording.
    if (with_board == 0 && views.frames == kGiveUpFrames && reader.rows().size() > kGiveUpFrames) {
      views.gave_up = true;
      break;
    }
    if (!found) continue;
    cv::cornerSubPix(gray, corners, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
    views.corners.push_back(std::move(corners));
    views.index.push_back(reader.rows()[i].index);
  }
  if (tty) std::fputc('\n', stderr);
  std::fprintf(stderr, "calibrate camera: the board was found in %zu of %zu frames\n",
               views.corners.size(), views.frames);
  return views;
}

// Views closer than this to a kept one (mean corner distance) add nothing:
// twelve frames of a board that did not move are one view.
constexpr double kDistinctViewPx = 1.0;
// A calibration is refused when its focal lengths are known no better than
// this (relative 1-sigma), or when the views left out of it are reprojected
// worse than kMaxHeldOutPx and kMaxHeldOutRatio times the fit's RMS: it
// fits the views it saw and not the camera.
constexpr double kMaxCheckerboardFocalSigma = 0.01;
constexpr double kMaxHeldOutPx = 1.0;
constexpr double kMaxHeldOutRatio = 3.0;
// A view is flagged when left out it is reprojected this many times worse
// than the median view (and worse than 0.5 px).
constexpr double kOutlierRatio = 4.0;
// Leave-one-out beyond this many views leaves out folds of views.
constexpr size_t kMaxFolds = 30;

// Drops views that repeat an earlier one; returns how many were dropped.
size_t keep_distinct_views(Views* views) {
  Views kept;
  kept.frames = views->frames;
  for (size_t v = 0; v < views->corners.size(); ++v) {
    bool repeat = false;
    for (const auto& other : kept.corners) {
      double sum = 0.0;
      for (size_t c = 0; c < other.size(); ++c)
        sum += std::hypot(other[c].x - views->corners[v][c].x, other[c].y - views->corners[v][c].y);
      if (sum / static_cast<double>(other.size()) < kDistinctViewPx) repeat = true;
    }
    if (repeat) continue;
    kept.corners.push_back(views->corners[v]);
    kept.index.push_back(views->index[v]);
  }
  const size_t dropped = views->corners.size() - kept.corners.size();
  *views = std::move(kept);
  return dropped;
}

double view_rms_px(const std::vector<cv::Point3f>& model, const std::vector<cv::Point2f>& corners,
                   const cv::Mat& k, const cv::Mat& dist) {
  cv::Mat rvec, tvec;
  cv::solvePnP(model, corners, k, dist, rvec, tvec);
  std::vector<cv::Point2f> projected;
  cv::projectPoints(model, rvec, tvec, k, dist, projected);
  double sum = 0.0;
  for (size_t c = 0; c < corners.size(); ++c) {
    const double d = std::hypot(projected[c].x - corners[c].x, projected[c].y - corners[c].y);
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(corners.size()));
}

// Each view's RMS reprojection error by a camera calibrated without it
// (cross-validation: folds of views when there are more than kMaxFolds).
std::vector<double> held_out_errors_px(const std::vector<cv::Point3f>& model, const Views& views,
                                       const cv::Size& size, const cv::Mat& k0,
                                       const cv::Mat& dist0) {
  const size_t n = views.corners.size();
  const size_t folds = std::min(n, kMaxFolds);
  std::vector<double> errors(n, 0.0);
  for (size_t fold = 0; fold < folds; ++fold) {
    std::vector<std::vector<cv::Point3f>> object;
    std::vector<std::vector<cv::Point2f>> corners;
    for (size_t v = 0; v < n; ++v)
      if (v % folds != fold) {
        object.push_back(model);
        corners.push_back(views.corners[v]);
      }
    cv::Mat k = k0.clone(), dist = dist0.clone();
    std::vector<cv::Mat> rvecs, tvecs;
    cv::calibrateCamera(object, corners, size, k, dist, rvecs, tvecs,
                        cv::CALIB_USE_INTRINSIC_GUESS);
    for (size_t v = fold; v < n; v += folds)
      errors[v] = view_rms_px(model, views.corners[v], k, dist);
  }
  return errors;
}

void run_calibrate_camera(const CameraArgs& args) {
  Result<BoardSpec> board = parse_board_spec(args.board);
  if (!board) {
    std::fprintf(stderr, "ceilposectl calibrate camera: %s\n", board.error().message.c_str());
    return set_exit_code(kExitUsage);
  }
  if (auto clash =
          check_outputs_are_not_inputs({{"--out", args.out_file}}, {}, {{"--replay", args.dir}});
      !clash) {
    std::fprintf(stderr, "ceilposectl calibrate camera: %s\n", clash.error().message.c_str());
    return set_exit_code(kExitUsage);
  }
  auto reader = RecordingReader::open(args.dir);
  if (!reader) {
    std::fprintf(stderr, "ceilposectl calibrate camera: %s\n", reader.error().message.c_str());
    return set_exit_code(kExitBadInput);
  }
  auto views = find_boards(*reader, *board);
  if (!views) {
    std::fprintf(stderr, "ceilposectl calibrate camera: %s\n", views.error().message.c_str());
    return set_exit_code(kExitBadInput);
  }
  if (views->gave_up) {
    std::fprintf(stderr,
                 "ceilposectl calibrate camera: the %dx%d board was not found in the first %zu "
                 "frames; stopped. Is --board right? It counts inner corners, columns first (a "
                 "board of 10 x 7 squares is 9x6)\n",
                 board->cols, board->rows, kGiveUpFrames);
    return set_exit_code(kExitFailure);
  }
  const size_t found = views->corners.size();
  const size_t repeats = keep_distinct_views(&*views);
  const size_t n = views->corners.size();
  if (n < static_cast<size_t>(kMinViews)) {
    std::fprintf(stderr,
                 "ceilposectl calibrate camera: the %dx%d board was found in %zu of %zu frames",
                 board->cols, board->rows, found, views->frames);
    if (repeats > 0)
      std::fprintf(stderr, ", %zu of them repeating another view (within %.1f px): %zu distinct",
                   repeats, kDistinctViewPx, n);
    std::fprintf(stderr,
                 "; at least %d views are needed (check --board's inner-corner count, lighting and "
                 "focus; move and tilt the board between views)\n",
                 kMinViews);
    return set_exit_code(kExitFailure);
  }
  if (repeats > 0)
    std::fprintf(stderr, "calibrate camera: %zu views repeat another (within %.1f px): not used\n",
                 repeats, kDistinctViewPx);
  std::vector<cv::Point3f> model;
  for (int r = 0; r < board->rows; ++r)
    for (int c = 0; c < board->cols; ++c)
      model.emplace_back(static_cast<float>(c * board->square_m),
                         static_cast<float>(r * board->square_m), 0.0f);
  const std::vector<std::vector<cv::Point3f>> object(n, model);
  const CameraIntrinsics& declared = reader->camera().intrinsics;
  const cv::Size size(declared.width, declared.height);
  cv::Mat k, dist;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_intrinsics, std_extrinsics, per_view;
  const double rms = cv::calibrateCamera(object, views->corners, size, k, dist, rvecs, tvecs,
                                         std_intrinsics, std_extrinsics, per_view);
  std::fprintf(stderr, "calibrate camera: %zu views, RMS reprojection error %.3f px\n", n, rms);
  const std::vector<double> held_out = held_out_errors_px(model, *views, size, k, dist);
  std::vector<double> sorted = held_out;
  std::sort(sorted.begin(), sorted.end());
  const double median_held_out = sorted[n / 2];
  double held_out_sq = 0.0;
  for (double e : held_out) held_out_sq += e * e;
  const double held_out_rms = std::sqrt(held_out_sq / static_cast<double>(n));
  double max_tilt_deg = 0.0;
  size_t flagged = 0;
  for (size_t v = 0; v < n; ++v) {
    cv::Mat r;
    cv::Rodrigues(rvecs[v], r);
    const double tilt_deg = kDegPerRad * std::acos(std::min(1.0, std::abs(r.at<double>(2, 2))));
    max_tilt_deg = std::max(max_tilt_deg, tilt_deg);
    const bool outlier = held_out[v] > std::max(0.5, kOutlierRatio * median_held_out);
    flagged += outlier ? 1 : 0;
    std::fprintf(stderr,
                 "  view %3zu (frame %lld): %.3f px in the fit, %.3f px left out, board tilted "
                 "%.1f deg%s\n",
                 v, static_cast<long long>(views->index[v]),
                 per_view.at<double>(static_cast<int>(v)), held_out[v], tilt_deg,
                 outlier ? "  <- does not fit the others (blurred, moved, or a wrong corner "
                           "order?): consider removing it"
                         : "");
  }
  std::fprintf(stderr,
               "calibrate camera: left out of the fit, the views reproject at %.3f px RMS "
               "(median %.3f px)%s\n",
               held_out_rms, median_held_out,
               flagged > 0 ? "; some views do not fit (marked above)" : "");
  // Coverage: which cells of a 4 x 4 grid over the image have corners.
  bool cell[4][4] = {};
  for (const auto& view : views->corners)
    for (const cv::Point2f& p : view)
      cell[std::clamp(static_cast<int>(4 * p.y / size.height), 0, 3)]
          [std::clamp(static_cast<int>(4 * p.x / size.width), 0, 3)] = true;
  int covered = 0;
  for (const auto& row : cell)
    for (bool c : row) covered += c ? 1 : 0;
  if (covered < kMinCoverage * 16)
    std::fprintf(stderr,
                 "calibrate camera: warning: the board reached only %d of 16 image cells (4 x 4): "
                 "distortion is extrapolated where it never was; show it in the corners too\n",
                 covered);
  if (max_tilt_deg < kMinTiltDeg)
    std::fprintf(stderr,
                 "calibrate camera: warning: the board never tilted more than %.1f deg: the focal "
                 "length is weakly determined; tilt it 20-45 deg in several directions\n",
                 max_tilt_deg);
  CameraIntrinsics out = declared;
  out.fx = k.at<double>(0, 0);
  out.fy = k.at<double>(1, 1);
  out.cx = k.at<double>(0, 2);
  out.cy = k.at<double>(1, 2);
  for (int c = 0; c < 5; ++c) out.distortion[static_cast<size_t>(c)] = dist.at<double>(c);
  const double sigma_fx = std_intrinsics.at<double>(0), sigma_fy = std_intrinsics.at<double>(1);
  std::fprintf(stderr,
               "calibrate camera: fx %.2f +- %.2f, fy %.2f +- %.2f, cx %.2f +- %.2f, cy %.2f +- "
               "%.2f px; k1 %.5f k2 %.5f p1 %.6f p2 %.6f k3 %.5f\n",
               out.fx, sigma_fx, out.fy, sigma_fy, out.cx, std_intrinsics.at<double>(2), out.cy,
               std_intrinsics.at<double>(3), out.distortion[0], out.distortion[1],
               out.distortion[2], out.distortion[3], out.distortion[4]);
  std::string refusal;
  char why[256];
  if (!(sigma_fx <= kMaxCheckerboardFocalSigma * out.fx &&
        sigma_fy <= kMaxCheckerboardFocalSigma * out.fy)) {
    std::snprintf(why, sizeof why,
                  "the focal lengths are undetermined (1-sigma %.1f and %.1f px, over %.0f %%): "
                  "the views are too alike; tilt the board 20-45 deg in several directions",
                  sigma_fx, sigma_fy, 100.0 * kMaxCheckerboardFocalSigma);
    refusal = why;
  } else if (!std::isfinite(held_out_rms) ||
             (held_out_rms > kMaxHeldOutPx && held_out_rms > kMaxHeldOutRatio * rms)) {
    std::snprintf(why, sizeof why,
                  "the calibration does not generalise: views left out of the fit reproject at "
                  "%.3f px RMS against %.3f px in it (limits %.1f px and %.0fx)",
                  held_out_rms, rms, kMaxHeldOutPx, kMaxHeldOutRatio);
    refusal = why;
  }
  if (!refusal.empty()) {
    std::fprintf(stderr, "ceilposectl calibrate camera: %s; %s was not written\n", refusal.c_str(),
                 args.out_file.c_str());
    return set_exit_code(kExitFailure);
  }
  if (auto wrote = write_camera_info_file(args.out_file, out); !wrote) {
    std::fprintf(stderr, "ceilposectl calibrate camera: %s\n", wrote.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  std::fprintf(stderr,
               "calibrate camera: wrote %s (use it as --camera or camera.calibration_file)\n",
               args.out_file.c_str());
  set_exit_code(kExitOk);
}

struct MountArgs {
  ReplayArgs replay;
  std::string out_file = "mount.yaml";
  MountEstimateOptions estimate;
};

// Every frame's camera pose: the robot's pose as if the camera sat at the
// robot's origin with no mounting yaw (the rest of the mount, lens height
// and tilt, as configured).
class CameraTrack final : public PoseSink {
 public:
  void consume(const Localization& loc) override {
    if (!loc.measured.valid) return;
    samples.push_back({loc.frame.timestamp_ns * 1e-9, loc.measured.pose.x_m, loc.measured.pose.y_m,
                       loc.measured.pose.yaw_rad});
  }
  std::vector<CameraSample> samples;
};

// The replay's files (--replay, --config, --camera, --map) as a calibration's
// inputs, for check_outputs_are_not_inputs.
std::vector<NamedPath> replay_input_files(const ReplayArgs& replay) {
  return {{"--config", replay.config_file},
          {"--camera", replay.calibration.camera_file},
          {"--map", replay.calibration.map_file}};
}

// What the estimate read the drive as, segment by segment, and what it used.
void print_mount_report(const MountEstimate& m, const std::vector<CameraSample>& samples) {
  for (const MotionSegment& g : m.segments) {
    std::fprintf(stderr, "  %6.2f-%6.2f s  %-40s", samples[g.first].t_s - samples.front().t_s,
                 samples[g.last].t_s - samples.front().t_s, to_string(g.kind));
    if (g.kind == MotionSegment::kStraight || g.kind == MotionSegment::kStraightBackwards)
      std::fprintf(stderr, " %.2f m, line RMS %.2f mm\n", g.length_m, 1000.0 * g.rms_m);
    else
      std::fprintf(stderr, " %.0f deg, camera circle radius %.1f mm, RMS %.2f mm\n",
                   g.turned_rad * kDegPerRad, 1000.0 * g.radius_m, 1000.0 * g.rms_m);
  }
  std::fprintf(stderr,
               "calibrate mount: used %d turns in place (%.0f deg, camera circle RMS %.2f mm), %d "
               "straight drives (%.2f m, line RMS %.2f mm)\n",
               m.turn_segments, m.turned_rad * kDegPerRad, 1000.0 * m.circle_rms_m,
               m.straight_segments, m.driven_m, 1000.0 * m.line_rms_m);
  if (m.backwards_m > 0.0)
    std::fprintf(stderr,
                 "calibrate mount: %.2f m of the straight drive went backwards (the image top "
                 "pointed against the motion); taken as reversing: the image top faces the "
                 "robot's forward axis (SPEC §3)\n",
                 m.backwards_m);
}

void run_calibrate_mount(MountArgs& args) {
  if (auto clash =
          check_outputs_are_not_inputs({{"--out", args.out_file}}, replay_input_files(args.replay),
                                       {{"--replay", args.replay.dir}});
      !clash) {
    std::fprintf(stderr, "ceilposectl calibrate mount: %s\n", clash.error().message.c_str());
    return set_exit_code(kExitUsage);
  }
  ReplaySetup setup;
  args.replay.mode_text = "lsq";
  int rc = prepare_replay(args.replay, "calibrate mount", &setup);
  if (rc != kExitOk) return set_exit_code(rc);
  setup.config.mount.offset_forward_m = setup.config.mount.offset_left_m = 0.0;
  setup.config.mount.yaw_rad = 0.0;
  CameraTrack track;
  PoseSink* sinks[] = {&track};
  rc = run_replay(args.replay, "calibrate mount", setup, sinks);
  if (rc != kExitOk) return set_exit_code(rc);
  std::fprintf(stderr, "calibrate mount: %zu of %zu frames localized\n", track.samples.size(),
               setup.reader->rows().size());
  auto m = estimate_mount(track.samples, args.estimate);
  if (!m) {
    std::fprintf(stderr, "ceilposectl calibrate mount: %s\n", m.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  print_mount_report(*m, track.samples);
  std::fprintf(stderr,
               "calibrate mount: camera %.2f +- %.2f mm forward, %.2f +- %.2f mm left of the "
               "robot origin, turned %.3f +- %.3f deg\n",
               1000.0 * m->offset_forward_m, 1000.0 * m->sigma_forward_m, 1000.0 * m->offset_left_m,
               1000.0 * m->sigma_left_m, m->yaw_rad * kDegPerRad, m->sigma_yaw_rad * kDegPerRad);
  const MountFragment fragment =
      fragment_of(*m, setup.config.mount,
                  "ceilposectl calibrate mount --replay " + args.replay.dir + ": " +
                      std::to_string(m->turn_segments) + " turns in place (" +
                      std::to_string(std::lround(m->turned_rad * kDegPerRad)) + " deg), " +
                      std::to_string(m->straight_segments) + " straight drives.");
  if (auto wrote = write_mount_fragment(args.out_file, fragment); !wrote) {
    std::fprintf(stderr, "ceilposectl calibrate mount: %s\n", wrote.error().message.c_str());
    return set_exit_code(kExitFailure);
  }
  std::fprintf(stderr, "calibrate mount: wrote %s\n", args.out_file.c_str());
  set_exit_code(kExitOk);
}

void add_calibrate_mount_command(CLI::App* calibrate) {
  auto args = std::make_shared<MountArgs>();
  CLI::App* mount = calibrate->add_subcommand(
      "mount",
      "The camera's place on the robot (offset forward and left of the robot origin, mounting "
      "yaw) from a recording in which the robot turns in place (360 deg or more in total) and "
      "drives straight (1 m or more): turning in place, the camera circles a still centre (the "
      "robot's origin); driving straight, it moves along the robot's heading. Jumps, time gaps, "
      "pauses and changes of motion end a segment; arcs (turning while driving) and circles "
      "about a moving centre are not used; reversing is named. Prints each segment, the mount "
      "with its 1-sigma, and writes a configuration fragment (mount: section) usable as "
      "--config. The lens height and tilt are the configuration's.\n"
      "Exit 0 ok, 1 the recording lacks the turn or the drive, or determines the mount worse "
      "than 1 mm / 0.1 deg (says which, writes nothing), or cannot write, 2 usage (also --out "
      "being an input), 4 malformed recording, configuration, map or camera file.");
  mount->add_option("--replay", args->replay.dir, "Recording of the turns and drives")->required();
  mount->add_option("--config", args->replay.config_file,
                    "Configuration (ceiling, camera, lens height; its mount offset and yaw are "
                    "what is measured)");
  add_calibration_options(mount, &args->replay.calibration);
  mount->add_option("--out", args->out_file, "Configuration fragment to write")
      ->capture_default_str();
  add_max_offset_option(mount, &args->estimate.max_offset_m);
  mount->callback([args] { run_calibrate_mount(*args); });
}

void add_calibrate_command(CLI::App& app) {
  CLI::App* calibrate =
      app.add_subcommand("calibrate",
                         "Calibrate the camera's intrinsics, its mount on the robot, or both at "
                         "once under a surveyed ceiling (SPEC §10)");
  calibrate->require_subcommand(1);
  auto cam = std::make_shared<CameraArgs>();
  CLI::App* camera = calibrate->add_subcommand(
      "camera",
      "Intrinsics from a recording of a checkerboard (OpenCV findChessboardCorners, cornerSubPix, "
      "calibrateCamera): fx, fy, cx, cy and plumb_bob, written as ROS camera_info YAML (SPEC "
      "§9). Prints the RMS and per-view reprojection errors in px; warns when the views do not "
      "cover the image or the board never tilts; refuses with fewer than 10 views.\n"
      "Exit 0 ok, 1 too few views or cannot write, 2 usage, 4 malformed recording.");
  camera->add_option("--replay", cam->dir, "Recording of the board (SPEC §4)")->required();
  camera
      ->add_option("--board", cam->board,
                   "checkerboard:COLSxROWS:SQUARE_M (inner corners as OpenCV counts them, "
                   "square side in metres)")
      ->required();
  camera->add_option("--out", cam->out_file, "camera_info file to write")->capture_default_str();
  camera->callback([cam] { run_calibrate_camera(*cam); });
  add_calibrate_mount_command(calibrate);
  add_calibrate_robot_command(calibrate);
}

const CommandRegistrar kCalibrateRegistrar{"calibrate", &add_calibrate_command};

}  // namespace
}  // namespace ceilpose::ctl
