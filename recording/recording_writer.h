#pragma once
// Writer of the recording format of SPEC §4. The header of frames.csv is
// fixed by the first append(): with ground-truth columns when that frame has
// ground truth; every later frame must agree.
//
// Thread safety: one thread at a time.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "core/image.h"
#include "core/pose.h"
#include "core/result.h"
#include "recording/recording_reader.h"

namespace ceilpose {

class RecordingWriter {
 public:
  // Creates `dir` (or uses it when it exists and is empty), writes
  // recording.yaml and creates frames/. Refuses a non-empty existing dir.
  static Result<RecordingWriter> create(const std::string& dir, const RecordingCamera& camera);

  RecordingWriter(RecordingWriter&&) noexcept;
  RecordingWriter& operator=(RecordingWriter&&) noexcept;
  // Closes frames.csv if close() was not called; errors are then lost, so
  // call close().
  ~RecordingWriter();

  // Writes frames/NNNNNN.png (or .jpg when jpeg_quality > 0, quality 1..100)
  // and appends the CSV row. Accepts RGB24, BGR24 and GRAY8 frames of the
  // camera's size, and MJPEG payloads, which are stored as they are (.jpg).
  // Timestamps must not decrease.
  Result<void> append(const ImageView& frame, int64_t timestamp_ns, const Pose2D* ground_truth,
                      int jpeg_quality = 0);

  Result<void> close();  // flushes frames.csv

  size_t frames_written() const;

 private:
  RecordingWriter();
  Result<void> append_lines(const char* data, size_t size);
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace ceilpose
