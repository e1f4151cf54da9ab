#pragma once
// PNG files with libpng: a recording's frames (SPEC §4) and annotated
// pictures. Error messages describe the defect; callers prefix the file.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "core/result.h"

namespace ceilpose::codec {

// Decodes an 8-bit PNG: grey into kGray8, RGB and palette into kRgb24.
// Refuses 16-bit samples and alpha channels by name. `out` is resized; its
// storage is reused when the size repeats.
Result<void> decode_png(const uint8_t* data, size_t size, Image* out);

// Encodes a kGray8, kRgb24 or kBgr24 image at zlib level `zlib_level` (0-9;
// 1 keeps up with a camera) into `out`, whose capacity is reused.
Result<void> encode_png(const ImageView& src, int zlib_level, std::vector<uint8_t>* out);

}  // namespace ceilpose::codec
