#pragma once
// A fixed set of owned frame images for sources that produce their own pixels
// (replay, synthetic): the analogue of a driver's buffer set. Allocates only
// in resize(); acquire/release are O(slots) scans of a handful of flags.
//
// Thread: the source's thread only (the capture thread).
#include <cstdint>
#include <vector>

#include "core/image.h"

namespace ceilpose::capture {

class FramePool {
 public:
  void resize(int slots, int width, int height, PixelFormat format) {
    slots_.assign(static_cast<size_t>(slots), Slot{});
    for (auto& s : slots_) s.image.resize(width, height, format);
  }
  int size() const { return static_cast<int>(slots_.size()); }

  // A free slot's image, marked busy, and its index; nullptr when every slot
  // is held downstream.
  Image* acquire(int32_t* index) {
    for (size_t i = 0; i < slots_.size(); ++i) {
      if (!slots_[i].busy) {
        slots_[i].busy = true;
        *index = static_cast<int32_t>(i);
        return &slots_[i].image;
      }
    }
    return nullptr;
  }
  // Frees a slot again (a slot whose content could not be produced, or a
  // released frame). Out-of-range indices are ignored.
  void release(int32_t index) {
    if (index >= 0 && static_cast<size_t>(index) < slots_.size()) {
      slots_[static_cast<size_t>(index)].busy = false;
    }
  }

 private:
  struct Slot {
    Image image;
    bool busy = false;
  };
  std::vector<Slot> slots_;
};

}  // namespace ceilpose::capture
