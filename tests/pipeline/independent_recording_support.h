#pragma once
// SPEC §4 recordings written from §4's text alone (not by recording/'s
// writer), so that a format detail the reader and writer share by accident
// would show when the project reads them.
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>

#include "independent_renderer_support.h"

namespace ceilpose::testing::xcheck {

// How frames are stored: SPEC §4 allows 8-bit PNG, RGB or greyscale, and JPEG.
enum class XFrameFile { kPngRgb, kPngGrey, kJpeg };

class XRecordingWriter {
 public:
  // Creates `dir` (emptied first) with recording.yaml for `camera`, a
  // `source` line and a frames.csv whose header carries an extra column
  // (exposure_us) that readers must ignore. `jpeg_quality` applies to kJpeg.
  XRecordingWriter(const std::filesystem::path& dir, const XCamera& camera, XFrameFile file,
                   int jpeg_quality = 90);

  // Stores an 8-bit RGB frame as the next row, with `truth` as ground truth,
  // at 30 frames/s from t = 1 s. False (and a message in error()) when the
  // image cannot be written.
  bool add(const cv::Mat& rgb, const XPose& truth);

  const std::string& error() const { return error_; }
  int frames() const { return frames_; }

 private:
  std::filesystem::path dir_;
  XFrameFile file_;
  int jpeg_quality_;
  std::ofstream csv_;
  int frames_ = 0;
  std::string error_;
};

}  // namespace ceilpose::testing::xcheck
