#pragma once
// Why a frame gave no pose: one name per stage that can refuse a frame, set
// where the refusal is decided and carried unchanged to every output (SPEC §5
// `refusal` of `locate`, `ceilposectl status`, the shared-memory and DDS
// status records, the daemon's periodic problem line). The enumerators'
// values are part of the shared-memory and DDS layouts: append, never
// reorder.
#include <array>
#include <atomic>
#include <cstdint>
#include <string_view>

namespace ceilpose {

enum class Refusal : uint8_t {
  kNone = 0,             // not refused: the frame gave a pose
  kUnusableFrame,        // empty, compressed, wrong size or stride
  kNoisyFrame,           // classification abandoned: too many colour runs
  kNoMarkers,            // no red/green rectangle pair in view
  kUnreadableMarkers,    // pairs seen, none decoded (cut by the border, blurred, ambiguous dots)
  kInconsistentMarkers,  // codes contradict the dark area, or markers disagree on the grid
  kNoWholeMarker,        // decoded markers, none with its whole outline inside the frame
  kLoneMarkerUnclear,    // a single marker whose dots do not read clearly enough
  kWrongHeights,         // the markers' spacing contradicts the configured heights
  kTooFewMarkers,        // the requested mode needs more consistent markers (barycentric: 3)
  kSolverRejected,       // the solver did not converge or its residual was too large
  kFilterRejected,       // measured, but the temporal filter gave no pose
  kUnmappedMarkers,      // whole markers decoded, none of them on the ceiling map (SPEC §8)
  kNoColour,             // a greyscale frame: the markers are found by their red and green
  kCount,
};

inline constexpr int kRefusalCount = static_cast<int>(Refusal::kCount);

// snake_case name (SPEC §5): "unusable_frame", ...; "none" for kNone;
// "unknown" out of range.
std::string_view to_string(Refusal refusal);
// The name for an index read from shared memory or DDS ("unknown" beyond).
std::string_view refusal_name(int index);
// One human phrase for logs, counting frames: "frames without a rectangle pair".
std::string_view describe(Refusal refusal);

// Frames per refusal, kNone counting the frames that gave a pose. One
// writer (the thread that localizes); any thread may read: the counts are
// relaxed atomics, so a reader sees each count whole but not all counts of
// the same instant. Allocation-free.
class RefusalHistogram {
 public:
  using Counts = std::array<uint64_t, kRefusalCount>;

  void count(Refusal refusal) noexcept {
    const auto i = static_cast<size_t>(refusal);
    if (i < counts_.size()) counts_[i].fetch_add(1, std::memory_order_relaxed);
  }
  uint64_t operator[](Refusal refusal) const noexcept {
    const auto i = static_cast<size_t>(refusal);
    return i < counts_.size() ? counts_[i].load(std::memory_order_relaxed) : 0;
  }
  Counts snapshot() const noexcept {
    Counts out{};
    for (size_t i = 0; i < out.size(); ++i) out[i] = counts_[i].load(std::memory_order_relaxed);
    return out;
  }

 private:
  std::array<std::atomic<uint64_t>, kRefusalCount> counts_{};
};

}  // namespace ceilpose
