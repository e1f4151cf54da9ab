// Detection quality on the simulator's named scenario sets: how many of the
// whole markers in view are decoded, how many decoded codes are wrong, how
// far the marker-centre points lie from the projection of the true centres,
// and what the pipeline's own pose (auto mode) makes of them.
//   ninja -C build detect_eval && build/bench/pipeline/detect_eval stress 200
// Options by environment: WIDTH (320/640/1280, field of view kept), K1
// (radial distortion k1, with k2 = 0.1·k1, in both renderer and pipeline),
// SEED (scenario seed, default 7), DUMP=1 (per wrongly decoded marker: frame,
// effects, codes, slot ratios, and what the frame's pose made of it), SLOTS=1
// (the highest ratio a printed red dot read and the lowest an empty slot
// read, over every pair within 3 px of a true marker, decoded or not).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "pipeline/dot_reader.h"
#include "pipeline/pipeline.h"
#include "pipeline/rectangle_ends.h"
#include "sim/renderer.h"
#include "sim/scenarios.h"
#include "sim/visibility.h"

namespace ceilpose {
namespace {

// The marker whose projected centre is nearest (u, v): the truth behind a
// decoded marker.
void nearest_marker(const PipelineConfig& config, const CameraPose& camera, double u, double v,
                    int* i_out, int* j_out, double* err_px) {
  *err_px = 1e9;
  for (int i = 0; i < config.layout.codes(); ++i) {
    for (int j = 0; j < config.layout.codes(); ++j) {
      double pu = 0.0, pv = 0.0;
      if (!project_world_point(config.intrinsics, camera, config.layout.marker_centre_w(i, j), &pu,
                               &pv))
        continue;
      const double e = std::hypot(pu - u, pv - v);
      if (e < *err_px) *err_px = e, *i_out = i, *j_out = j;
    }
  }
}

// One line for a wrongly decoded marker, with the slot ratios of its pair.
void dump_wrong(const Pipeline& pipeline, const ImageView& image, const sim::ScenarioFrame& f,
                size_t frame_index, const CameraPose& camera, const MarkerObservation& o,
                const FrameResult& result) {
  const PipelineConfig& config = pipeline.config();
  int ti = -1, tj = -1;
  double err_px = 0.0;
  nearest_marker(config, camera, o.centre_u_px, o.centre_v_px, &ti, &tj, &err_px);
  std::printf(
      "WRONG frame %zu seed %llu | defocus %.2f motion %.2f px gain %.2f | read (%d,%d) true "
      "(%d,%d) at %.1f px | centre (%.1f, %.1f) | markers %d valid %d pose error %.3f m\n",
      frame_index, static_cast<unsigned long long>(f.seed), f.effects.defocus_sigma_px,
      f.effects.motion_blur_px, f.effects.gain, o.code_i, o.code_j, ti, tj, err_px, o.centre_u_px,
      o.centre_v_px, result.marker_count, result.estimate.valid ? 1 : 0,
      std::hypot(result.estimate.pose.x_m - f.pose.x_m, result.estimate.pose.y_m - f.pose.y_m));
  const auto rects = pipeline.rectangles();
  for (const MarkerPair& p : pipeline.pairs()) {
    const MarkerFrame m = marker_frame(rects[p.red], rects[p.green], config.layout);
    if (std::hypot(m.centre_u_px - o.centre_u_px, m.centre_v_px - o.centre_v_px) > 1e-6) continue;
    const double px_per_m = std::hypot(m.north_u, m.north_v);
    const double red_dot_px = config.layout.red_dot_n_m * px_per_m;
    const double blur_px = edge_spread_px(image, m, true, config.layout);
    const float threshold = dot_threshold_ratio(config.detector, blur_px, red_dot_px);
    std::printf(
        "  px/m %.1f red dot %.2f px blur %.2f px threshold %.3f | red area %.0f long %.1f "
        "dark %.0f | green area %.0f long %.1f dark %.0f\n",
        px_per_m, red_dot_px, blur_px, threshold, rects[p.red].area_px, rects[p.red].long_px,
        rects[p.red].dark_px, rects[p.green].area_px, rects[p.green].long_px,
        rects[p.green].dark_px);
    for (bool red : {true, false}) {
      const CodeReading c = read_code(image, m, red, config.layout, config.detector, threshold);
      std::printf("  %s code %d margin %.3f ratios", red ? "red  " : "green", c.code, c.margin);
      for (int k = 0; k < config.layout.bits; ++k) std::printf(" %.3f", c.ratio[k]);
      std::printf("\n");
    }
  }
  for (int k = 0; k < result.marker_count; ++k) {
    const MarkerObservation& q = result.markers[k];
    std::printf("  decoded (%d,%d) at (%.1f, %.1f) quality %.2f\n", q.code_i, q.code_j,
                q.centre_u_px, q.centre_v_px, q.quality);
  }
}

// Extremes of the slot ratios against the truth, for choosing thresholds.
struct SlotExtremes {
  double red_dot_max = 0.0, empty_min = 1e9;
  void add(const Pipeline& pipeline, const ImageView& image, const CameraPose& camera) {
    const PipelineConfig& config = pipeline.config();
    const auto rects = pipeline.rectangles();
    for (const MarkerPair& p : pipeline.pairs()) {
      if (rects[p.red].touches_border || rects[p.green].touches_border) continue;
      const MarkerFrame m = marker_frame(rects[p.red], rects[p.green], config.layout);
      int truth[2] = {-1, -1};
      double err_px = 0.0;
      nearest_marker(config, camera, m.centre_u_px, m.centre_v_px, &truth[0], &truth[1], &err_px);
      if (err_px > 3.0) continue;
      for (int c = 0; c < 2; ++c) {
        const CodeReading r = read_code(image, m, c == 0, config.layout, config.detector,
                                        config.detector.dot_threshold_ratio);
        if (!r.ok) continue;
        for (int k = 0; k < config.layout.bits; ++k) {
          if (!config.layout.slot_bit(truth[c], k)) {
            empty_min = std::min(empty_min, static_cast<double>(r.ratio[k]));
          } else if (c == 0) {
            red_dot_max = std::max(red_dot_max, static_cast<double>(r.ratio[k]));
          }
        }
      }
    }
  }
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))];
}

int run(const std::string& name, int frame_count) {
  sim::SceneOptions options;
  if (const char* w = std::getenv("WIDTH")) {
    const int width = std::atoi(w);
    const double scale = width / 640.0;
    options.intrinsics.width = width;
    options.intrinsics.height = width * 3 / 4;
    options.intrinsics.fx = options.intrinsics.fy = 530.0 * scale;
    options.intrinsics.cx = 0.5 * (width - 1);
    options.intrinsics.cy = 0.5 * (width * 3 / 4 - 1);
  }
  if (const char* k1 = std::getenv("K1")) {
    options.intrinsics.distortion[0] = std::atof(k1);
    options.intrinsics.distortion[1] = 0.1 * std::atof(k1);
  }
  sim::Renderer renderer(options);
  const Result<sim::Scenario> scenario =
      sim::make_scenario(name, options, frame_count,
                         std::getenv("SEED") ? std::strtoull(std::getenv("SEED"), nullptr, 10) : 7);
  if (!scenario) {
    std::fprintf(stderr, "detect_eval: %s\n", scenario.error().message.c_str());
    return 2;
  }
  PipelineConfig config;
  config.intrinsics = options.intrinsics;
  Pipeline pipeline(config);
  static FrameResult result;
  Image image;
  int whole = 0, found = 0, wrong = 0, frames_with_whole = 0, valid = 0, gross = 0;
  std::vector<double> centre_err_px, pose_err_m, depth_scale;
  const bool dump = std::getenv("DUMP") != nullptr;
  const bool slots = std::getenv("SLOTS") != nullptr;
  SlotExtremes extremes;
  MarkerRejects rejects;
  for (size_t index = 0; index < scenario->frames.size(); ++index) {
    const sim::ScenarioFrame& f = scenario->frames[index];
    renderer.render(f.pose, f.mount, f.effects, f.seed, &image);
    pipeline.process(image.view(), PositioningMode::kAuto, &result);
    rejects.cut += result.rejects.cut;
    rejects.blurred += result.rejects.blurred;
    rejects.ambiguous += result.rejects.ambiguous;
    rejects.inconsistent += result.rejects.inconsistent;
    const CameraPose camera = camera_pose_from_robot(f.pose, f.mount);
    if (slots) extremes.add(pipeline, image.view(), camera);
    const int in_view = sim::count_whole_markers(options, f.pose, f.mount);
    whole += in_view;
    frames_with_whole += in_view > 0 ? 1 : 0;
    int right = 0;
    for (int k = 0; k < result.marker_count; ++k) {
      const MarkerObservation& o = result.markers[k];
      double u = 0.0, v = 0.0;
      project_world_point(config.intrinsics, camera,
                          config.layout.marker_centre_w(o.code_i, o.code_j), &u, &v);
      const double err = std::hypot(o.centre_u_px - u, o.centre_v_px - v);
      if (err > 3.0) {
        ++wrong;
        if (dump) dump_wrong(pipeline, image.view(), f, index, camera, o, result);
        continue;
      }
      ++right;
      centre_err_px.push_back(err);
    }
    found += std::min(right, in_view);
    if (result.estimate.depth_scale > 0.0) depth_scale.push_back(result.estimate.depth_scale);
    if (result.estimate.valid) {
      ++valid;
      const double e =
          std::hypot(result.estimate.pose.x_m - f.pose.x_m, result.estimate.pose.y_m - f.pose.y_m);
      pose_err_m.push_back(e);
      if (e > 0.25 * config.layout.grid_m) ++gross;
    }
  }
  std::printf(
      "%-12s frames %4zu | whole markers %5d decoded %5d (%.1f %%) wrong codes %d | centre error "
      "median %.3f p99 %.3f px | valid %d/%d frames, position error median %.2f p99 %.2f mm, "
      "gross %d | refused: cut %d blurred %d ambiguous %d inconsistent %d\n",
      name.c_str(), scenario->frames.size(), whole, found, whole ? 100.0 * found / whole : 0.0,
      wrong, percentile(centre_err_px, 0.5), percentile(centre_err_px, 0.99), valid,
      frames_with_whole, 1e3 * percentile(pose_err_m, 0.5), 1e3 * percentile(pose_err_m, 0.99),
      gross, rejects.cut, rejects.blurred, rejects.ambiguous, rejects.inconsistent);
  if (!depth_scale.empty()) {
    // How far the markers' spacing puts the ceiling from the configured
    // heights (positioning refuses beyond max_depth_scale_error).
    std::printf("depth scale over %zu frames: min %.4f p1 %.4f median %.4f p99 %.4f max %.4f\n",
                depth_scale.size(), percentile(depth_scale, 0.0), percentile(depth_scale, 0.01),
                percentile(depth_scale, 0.5), percentile(depth_scale, 0.99),
                percentile(depth_scale, 1.0));
  }
  if (slots) {
    std::printf("slot ratios: printed red dots up to %.3f, empty slots down to %.3f\n",
                extremes.red_dot_max, extremes.empty_min);
  }
  return 0;
}

}  // namespace
}  // namespace ceilpose

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::printf("usage: detect_eval SCENARIO [FRAMES]   (env WIDTH, K1)\nscenarios:\n");
    for (const auto& [name, description] : ceilpose::sim::scenario_catalog())
      std::printf("  %-14s %s\n", name.c_str(), description.c_str());
    return argc < 2 ? 2 : 0;
  }
  return ceilpose::run(argv[1], argc > 2 ? std::atoi(argv[2]) : 100);
}
