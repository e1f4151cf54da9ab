#pragma once
// Conversions of captured frames to packed RGB24, for consumers that need one
// fixed layout (the recorder writes PNG; the pipeline may take YUYV directly).
#include "core/image.h"
#include "core/result.h"

namespace ceilpose::capture {

// Converts GREY, RGB24, BGR24, YUYV, NV12 or YUV420 into `out` (RGB24, or
// GREY kept as GREY when keep_gray); YUV with chroma interpolated at each
// pixel as the detector reads it (core/pixel_read.h), so that a recording
// replays with the edges the camera showed live. Allocates only when out's
// size changes. MJPEG is an error: sources decode it before delivery.
Result<void> to_rgb24(const ImageView& in, Image* out, bool keep_gray = true);

}  // namespace ceilpose::capture
