#pragma once
// Reader of the recording format of SPEC §4: recording.yaml, frames.csv and
// one PNG or JPEG file per frame. open() validates everything but the pixels;
// load_frame() checks one frame file's structure and decodes it.
//
// Beyond SPEC §4 the reader accepts, without loss of strictness: extra
// columns in any order, RFC 4180 quoted fields, CRLF line ends, a UTF-8
// byte-order mark, blank lines at the very end, a row whose three gt_* fields
// are all empty (that frame has no ground truth), `distortion` omitted (none),
// palette PNGs (decoded to RGB). Everything else that departs is an error.
//
// Thread safety: load_frame(i, out) and check_frame reuse the reader's own
// buffers (so that replay does not allocate per frame) and are for one thread
// at a time; load_frame(i, out, buffers) may run on several threads at once,
// each with its own DecodeBuffers (see FramePrefetcher).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/camera_model.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/result.h"

namespace ceilpose {

struct RecordingCamera {
  CameraIntrinsics intrinsics;
  std::string source;  // free text (recording.yaml `source`), may be empty
};

struct RecordingRow {
  int64_t index = 0;
  int64_t timestamp_ns = 0;
  std::string file;  // relative to the recording directory, as written in frames.csv
  bool has_ground_truth = false;
  Pose2D ground_truth;
  int csv_line = 0;  // 1-based line of this row in frames.csv (the header is line 1)
};

// Bytes of one decoded RGB frame of `width` x `height`: what decoding holds
// per copy of a frame.
inline size_t decoded_frame_bytes(int width, int height) {
  return static_cast<size_t>(width > 0 ? width : 0) * static_cast<size_t>(height > 0 ? height : 0) *
         3;
}

class RecordingReader {
 public:
  // Parses and validates recording.yaml and all of frames.csv (and that every
  // frame file exists). Errors name the file and line.
  static Result<RecordingReader> open(const std::string& dir);

  RecordingReader(RecordingReader&&) noexcept;
  RecordingReader& operator=(RecordingReader&&) noexcept;
  ~RecordingReader();

  const std::string& dir() const { return dir_; }
  const RecordingCamera& camera() const { return camera_; }
  const std::vector<RecordingRow>& rows() const { return rows_; }
  // True when frames.csv carries the gt_x_m, gt_y_m, gt_yaw_rad columns.
  bool has_ground_truth_columns() const { return has_ground_truth_columns_; }

  // Decodes frame i into `out` (RGB24 or GRAY8 as stored). Errors (missing,
  // truncated, not an image, wrong size, unsupported depth) name the file and
  // the frames.csv line. `out` keeps its buffer when the size does not change.
  Result<void> load_frame(size_t i, Image* out) const;

  // The encoded bytes and decoder output that loading a frame reuses.
  struct DecodeBuffers;
  struct DecodeBuffersDeleter {
    void operator()(DecodeBuffers* b) const;
  };
  static std::unique_ptr<DecodeBuffers, DecodeBuffersDeleter> make_decode_buffers();
  // load_frame with caller-owned buffers: safe to call concurrently from
  // threads that each pass their own.
  Result<void> load_frame(size_t i, Image* out, DecodeBuffers* buffers) const;

  // Reads frame i's file and checks its structure (signature, complete chunk
  // or marker sequence, size, bit depth) without decoding the pixels.
  Result<void> check_frame(size_t i) const;

  // "<dir>/<file> (frames.csv:<line>)": how errors about frame i name it.
  std::string frame_context(size_t i) const;
  // The error of frame i when memory ran out decoding it. Throws
  // std::bad_alloc if even this message cannot be made.
  std::string out_of_memory_error(size_t i) const;

 private:
  RecordingReader();
  Result<void> read_frame_file(size_t i, DecodeBuffers* buffers) const;
  Result<void> decode_frame(size_t i, Image* out, DecodeBuffers* buffers) const;

  std::string dir_;
  RecordingCamera camera_;
  std::vector<RecordingRow> rows_;
  std::vector<std::string> frame_paths_;  // dir_ + "/" + file, so loading builds no strings
  bool has_ground_truth_columns_ = false;
  std::unique_ptr<DecodeBuffers, DecodeBuffersDeleter> scratch_;
};

}  // namespace ceilpose
