#pragma once
// Stage 3: pairing each red rectangle with the green one that shares its
// long edge (the thesis's Couple_Rectangles). The red→green vector is the
// marker's West as seen in the image (SPEC §2), which fixes the heading.
#include <cstdint>
#include <span>
#include <vector>

#include "core/ceiling_layout.h"
#include "pipeline/detector_params.h"
#include "pipeline/rectangle_fit.h"

namespace ceilpose {

// What became of a pair once its dots were read (Pipeline sets it).
enum class PairOutcome : uint8_t {
  kDecoded,
  kCut,           // touching the frame border
  kBlurred,       // blur along North too wide for the red dots
  kUnreadable,    // slots outside the frame
  kAmbiguous,     // a slot too close to the dot threshold
  kInconsistent,  // dark area disagreeing with the code
  kOverflow,      // beyond kMaxMarkersPerFrame
};

struct MarkerPair {
  int red = -1;  // indices into the rectangle list
  int green = -1;
  double score = 0.0;  // sum of normalised deviations; 0 is a perfect pair
  PairOutcome outcome = PairOutcome::kDecoded;
};

// Preallocates for `max_rectangles` rectangles; single-threaded.
class MarkerPairer {
 public:
  explicit MarkerPairer(int max_rectangles);

  // Writes the pairs, each rectangle used at most once, best first; returns
  // how many (at most out.size()). Hot path: no allocation.
  int pair(std::span<const RectangleCandidate> rects, const CeilingLayout& layout,
           const DetectorParams& params, std::span<MarkerPair> out);

 private:
  std::vector<MarkerPair> candidates_;
  std::vector<uint8_t> used_;
};

}  // namespace ceilpose
