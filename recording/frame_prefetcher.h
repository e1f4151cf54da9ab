#pragma once
// Decodes the frames of a recording ahead of the caller, on worker threads,
// and hands them out in recording order. Offline localization (`ceilposectl
// locate`, `evaluate`) spends most of its time decoding PNGs (about 6–9 ms
// for a noisy 640x480 frame against 0.4 ms of pipeline), so decoding on every
// core makes it several times faster while the frames stay in order.
//
// A frame that fails to load is handed out in its place as the error, so the
// caller sees frames 0..k-1, then the error of frame k: nothing is skipped.
#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "core/image.h"
#include "core/result.h"
#include "recording/recording_reader.h"

namespace ceilpose {

class FramePrefetcher {
 public:
  // Starts `threads` decoding threads (at least 1) over the reader's frames
  // from `first`, fewer when their frames would not fit kDecodeBudgetBytes.
  // The reader must outlive the prefetcher.
  FramePrefetcher(const RecordingReader& reader, int threads, size_t first = 0);

  // What the frames held in decoding may take (issue 28: 32-Mpx frames on 16
  // threads took 4 GB and ended in std::bad_alloc): each thread holds its
  // frame twice (decoded BGR, and RGB in its slot) and two more slots wait.
  static constexpr size_t kDecodeBudgetBytes = size_t{1} << 30;
  // The threads `requested` frames of `frame_bytes` (RGB) may have.
  static int threads_within_budget(int requested, size_t frame_bytes);
  int threads() const { return static_cast<int>(workers_.size()); }
  ~FramePrefetcher();  // stops the workers and joins them; never waits for a decode to be consumed
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  // The next frame in order: blocks until it is decoded. The image stays valid
  // until the following call to next(). Returns the frame's load error in its
  // place; past the last frame returns an error saying so.
  Result<const Image*> next();

  // A sensible number of decoding threads for this machine.
  static int default_threads();

 private:
  struct Slot {
    Image image;
    Result<void> status;
    bool out_of_memory = false;  // its error is made by next(), not the worker
    size_t frame = 0;
    bool ready = false;
  };

  void worker(RecordingReader::DecodeBuffers* buffers);

  const RecordingReader& reader_;
  const size_t end_;
  std::vector<Slot> slots_;  // frame f lives in slots_[f % slots_.size()]
  std::vector<
      std::unique_ptr<RecordingReader::DecodeBuffers, RecordingReader::DecodeBuffersDeleter>>
      buffers_;
  std::mutex mutex_;
  std::condition_variable frame_ready_;  // a slot became ready
  std::condition_variable slot_free_;    // the consumer released a slot, or stop
  size_t next_claim_;                    // next frame a worker will decode
  size_t next_out_;                      // next frame next() returns
  bool holding_ = false;                 // the consumer holds the slot of next_out_ - 1
  bool stop_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace ceilpose
