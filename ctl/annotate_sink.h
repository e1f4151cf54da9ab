#pragma once
// `locate --annotate DIR`: one PNG per frame (or per refused frame) showing
// what the detector saw — every rectangle candidate, every red/green pair
// with its decoded code or the reason it was rejected, and the pose or the
// refusal — like apriltag's debug images, one picture per frame to scroll
// through.
#include <string>
#include <vector>

#include "pipeline/pose_sink.h"

namespace ceilpose::ctl {

class AnnotateSink final : public PoseSink {
 public:
  AnnotateSink(std::string dir, bool refused_only)
      : dir_(std::move(dir)), refused_only_(refused_only) {}
  void consume(const Localization& loc) override;
  // The first write error (file named), empty when every image was written.
  const std::string& error() const { return error_; }
  int written() const { return written_; }

 private:
  std::string dir_;
  bool refused_only_;
  std::string error_;
  int written_ = 0;
  std::vector<uint8_t> png_;  // one frame's encoded picture, reused
};

}  // namespace ceilpose::ctl
