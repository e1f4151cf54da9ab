#pragma once
// A rendered RGB frame as a camera hands it over: BGR24, YUYV 4:2:2 (BT.601
// limited range, V4L2's default quantisation for USB cameras; the chroma of
// each pixel pair averaged, as an ISP subsamples it), NV12 or YUV420 4:2:0
// (the chroma of each 2x2 block averaged; Pi cameras through libcamera) or
// GRAY8. The detector
// reads each natively; accuracy and speed are measured on them.
#include "core/image.h"

namespace ceilpose::sim {

Image convert_rgb(const Image& rgb, PixelFormat format);
// The same into `out`, which is resized (allocating) only when its size or
// format differ: the synthetic camera converts every frame so.
void convert_rgb(const Image& rgb, PixelFormat format, Image* out);

}  // namespace ceilpose::sim
