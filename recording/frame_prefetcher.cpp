#include "recording/frame_prefetcher.h"

#include <algorithm>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>

namespace ceilpose {

namespace {
// Beyond four threads PNG decoding outruns the pipeline on every machine we
// target (a robot's SBC has four cores), and each thread holds a frame.
constexpr int kMaxThreads = 4;
}  // namespace

int FramePrefetcher::default_threads() {
  const unsigned cpus = std::thread::hardware_concurrency();
  return std::clamp(static_cast<int>(cpus), 1, kMaxThreads);
}

int FramePrefetcher::threads_within_budget(int requested, size_t frame_bytes) {
  const size_t frames = kDecodeBudgetBytes / std::max<size_t>(frame_bytes, 1);
  const size_t fit = frames > 2 ? (frames - 2) / 2 : 0;
  return std::clamp(static_cast<int>(std::min<size_t>(fit, 1024)), 1, std::max(requested, 1));
}

FramePrefetcher::FramePrefetcher(const RecordingReader& reader, int threads, size_t first)
    : reader_(reader),
      end_(reader.rows().size()),
      next_claim_(std::min(first, reader.rows().size())),
      next_out_(next_claim_) {
  const CameraIntrinsics& k = reader.camera().intrinsics;
  threads = threads_within_budget(threads, decoded_frame_bytes(k.width, k.height));
  // One slot per worker to decode into, one the consumer holds, one spare so
  // that a worker never waits for the consumer to finish a frame.
  slots_.resize(static_cast<size_t>(threads) + 2);
  buffers_.reserve(static_cast<size_t>(threads));
  workers_.reserve(static_cast<size_t>(threads));
  for (int t = 0; t < threads; ++t) {
    buffers_.push_back(RecordingReader::make_decode_buffers());
    // A thread's stack may not fit under an address-space limit: decode on
    // the threads that started (unwinding past running threads would end
    // the program in std::terminate).
    try {
      workers_.emplace_back(&FramePrefetcher::worker, this, buffers_.back().get());
    } catch (const std::system_error& e) {
      buffers_.pop_back();
      if (workers_.empty())
        throw std::runtime_error(std::string("cannot start a frame-decoding thread: ") + e.what());
      break;
    }
  }
}

FramePrefetcher::~FramePrefetcher() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  slot_free_.notify_all();
  for (auto& w : workers_) w.join();
}

void FramePrefetcher::worker(RecordingReader::DecodeBuffers* buffers) {
  std::unique_lock lock(mutex_);
  for (;;) {
    // Frames from the one the consumer still holds onward occupy slots; a
    // worker may start a frame only when its slot is not among them.
    const auto may_claim = [&] {
      const size_t oldest = holding_ ? next_out_ - 1 : next_out_;
      return next_claim_ < oldest + slots_.size();
    };
    slot_free_.wait(lock, [&] { return stop_ || next_claim_ >= end_ || may_claim(); });
    if (stop_ || next_claim_ >= end_) return;
    const size_t frame = next_claim_++;
    Slot& slot = slots_[frame % slots_.size()];
    slot.ready = false;
    slot.frame = frame;
    lock.unlock();
    Result<void> status;
    bool out_of_memory = false;
    try {
      status = reader_.load_frame(frame, &slot.image, buffers);
    } catch (const std::bad_alloc&) {
      // Not even the error fitted: free this frame and let the consumer's
      // thread say it (an exception leaving a thread ends the program).
      slot.image = Image{};
      out_of_memory = true;
    }
    lock.lock();
    slot.status = std::move(status);
    slot.out_of_memory = out_of_memory;
    slot.ready = true;
    frame_ready_.notify_all();
  }
}

Result<const Image*> FramePrefetcher::next() {
  std::unique_lock lock(mutex_);
  if (holding_) {
    holding_ = false;
    slot_free_.notify_one();
  }
  if (next_out_ >= end_) {
    return make_error(reader_.dir() + ": read past the last frame (the recording has " +
                      std::to_string(end_) + " frames)");
  }
  Slot& slot = slots_[next_out_ % slots_.size()];
  frame_ready_.wait(lock, [&] { return slot.ready && slot.frame == next_out_; });
  ++next_out_;
  holding_ = true;
  if (slot.out_of_memory) return make_error(reader_.out_of_memory_error(slot.frame));
  if (!slot.status) return slot.status.error();
  return &slot.image;
}

}  // namespace ceilpose
