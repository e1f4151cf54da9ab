#include "ctl/survey_frames.h"

#include <cstdio>

#include "ctl/replay_run.h"

namespace ceilpose::ctl {
namespace {

class SurveyCollector final : public PoseSink {
 public:
  explicit SurveyCollector(std::vector<SurveyFrame>* frames) : frames_(frames) {}
  void consume(const Localization& loc) override {
    ++seen_;
    if (!loc.measured.valid) return;
    SurveyFrame f;
    f.timestamp_ns = loc.frame.timestamp_ns;
    f.robot = loc.measured.pose;
    for (const MarkerObservation& m : loc.markers)
      if (m.whole) f.markers.push_back(m);
    frames_->push_back(std::move(f));
    ++with_pose_;
  }
  size_t seen_ = 0, with_pose_ = 0;

 private:
  std::vector<SurveyFrame>* frames_;
};

}  // namespace

int collect_survey_frames(const FrameSources& sources, const char* command,
                          const CameraIntrinsics* camera, PipelineConfig* config,
                          std::vector<SurveyFrame>* frames) {
  frames->clear();
  bool first = true;
  for (const std::string& dir : sources.dirs) {
    ReplayArgs replay;
    replay.dir = dir;
    replay.config_file = sources.config_file;
    replay.calibration = sources.calibration;
    replay.mode_text = "lsq";
    ReplaySetup setup;
    int rc = prepare_replay(replay, command, &setup);
    if (rc != kExitOk) return rc;
    if (!sources.use_map) setup.config.map.reset();
    if (sources.zero_mount) {
      setup.config.mount.offset_forward_m = setup.config.mount.offset_left_m = 0.0;
      setup.config.mount.yaw_rad = 0.0;
    }
    if (camera != nullptr) setup.config.intrinsics = *camera;
    // The frames' poses only seed the adjustment, under a camera it is
    // about to find: the edge points, which measure each marker's size,
    // would refuse frames of a camera whose scale is still off.
    setup.config.positioning.lsq_edge_points = false;
    if (first) {
      *config = setup.config;
    } else if (!(setup.config.intrinsics == config->intrinsics)) {
      std::fprintf(stderr,
                   "ceilposectl %s: %s: its camera differs from %s's: one camera at a time\n",
                   command, dir.c_str(), sources.dirs.front().c_str());
      return kExitBadInput;
    }
    first = false;
    SurveyCollector collector(frames);
    PoseSink* sinks[] = {&collector};
    rc = run_replay(replay, command, setup, sinks);
    if (rc != kExitOk) return rc;
    std::fprintf(stderr, "%s: %s: %zu frames, %zu with a pose of their own\n", command, dir.c_str(),
                 collector.seen_, collector.with_pose_);
  }
  return kExitOk;
}

}  // namespace ceilpose::ctl
