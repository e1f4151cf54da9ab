#pragma once
// Conversions of captured frames to packed RGB24, for consumers that need one
// fixed layout (the recorder writes PNG; the pipeline may take YUYV directly).
#include "core/image.h"
#include "core/result.h"

namespace ceilpose::capture {

// Converts GREY, RGB24, BGR24 or YUYV into `out` (RGB24, or GREY kept as GREY
// when keep_gray). Allocates only when out's size changes. MJPEG is an error:
// sources decode it before delivery.
Result<void> to_rgb24(const ImageView& in, Image* out, bool keep_gray = true);

}  // namespace ceilpose::capture
