#include "independent_recording_support.h"

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace ceilpose::testing::xcheck {

XRecordingWriter::XRecordingWriter(const std::filesystem::path& dir, const XCamera& camera,
                                   XFrameFile file, int jpeg_quality)
    : dir_(dir), file_(file), jpeg_quality_(jpeg_quality) {
  std::filesystem::remove_all(dir_);
  std::filesystem::create_directories(dir_ / "frames");
  std::ofstream yaml(dir_ / "recording.yaml");
  yaml.precision(17);
  yaml << "format: ceilpose-recording\nversion: 1\ncamera:\n  width: " << camera.width
       << "\n  height: " << camera.height << "\n  fx: " << camera.fx << "\n  fy: " << camera.fy
       << "\n  cx: " << camera.cx << "\n  cy: " << camera.cy << "\n  distortion: [";
  for (size_t k = 0; k < camera.distortion.size(); ++k) {
    yaml << (k ? ", " : "") << camera.distortion[k];
  }
  yaml << "]   # k1 k2 p1 p2 k3\nsource: \"xcheck independent renderer\"\n";
  csv_.open(dir_ / "frames.csv");
  csv_.precision(17);  // ground truth read back to the last bit
  csv_ << "index,timestamp_ns,file,gt_x_m,gt_y_m,gt_yaw_rad,exposure_us\n";
}

bool XRecordingWriter::add(const cv::Mat& rgb, const XPose& truth) {
  char name[32];
  std::snprintf(name, sizeof name, "frames/%06d.%s", frames_,
                file_ == XFrameFile::kJpeg ? "jpg" : "png");
  cv::Mat stored;
  std::vector<int> params;
  if (file_ == XFrameFile::kPngGrey) {
    cv::cvtColor(rgb, stored, cv::COLOR_RGB2GRAY);
  } else {
    cv::cvtColor(rgb, stored, cv::COLOR_RGB2BGR);  // imwrite expects BGR
  }
  if (file_ == XFrameFile::kJpeg) params = {cv::IMWRITE_JPEG_QUALITY, jpeg_quality_};
  if (!cv::imwrite((dir_ / name).string(), stored, params)) {
    error_ = (dir_ / name).string() + ": cv::imwrite failed";
    return false;
  }
  csv_ << frames_ << ',' << 1000000000LL + frames_ * 33333333LL << ',' << name << ',' << truth.x_m
       << ',' << truth.y_m << ',' << truth.yaw_rad << ",8000\n";
  csv_.flush();
  ++frames_;
  return true;
}

}  // namespace ceilpose::testing::xcheck
