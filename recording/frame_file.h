#pragma once
// Structural check of one encoded frame file (PNG or JPEG) before decoding.
// Decoders may hand back a partially decoded image for a truncated file, so
// completeness is established here from the container itself.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/result.h"

namespace ceilpose {

enum class FrameEncoding : uint8_t { kPng, kJpeg };

const char* to_string(FrameEncoding e);

struct FrameFileInfo {
  FrameEncoding encoding = FrameEncoding::kPng;
  int width = 0;
  int height = 0;
  int channels = 0;          // after decoding: 1 grey, 2 grey+alpha, 3 colour, 4 colour+alpha
  int bit_depth = 0;         // bits per sample as stored
  int png_colour_type = -1;  // PNG IHDR colour type, -1 for JPEG
};

// Checks that `data` holds one complete PNG (signature, IHDR first, every
// chunk within the file, IEND present) or JPEG (SOI, a frame header before the
// scan, EOI at the end) and returns its header. The error message describes
// the defect only; the caller prefixes the file name.
Result<FrameFileInfo> inspect_frame_bytes(const uint8_t* data, size_t size);

// Whether the reader supports this frame: 8-bit grey or RGB (palette PNGs
// expand to RGB). The error names the unsupported depth or colour type.
Result<void> check_supported_frame(const FrameFileInfo& info);

}  // namespace ceilpose
