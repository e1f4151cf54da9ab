#include "recording/frame_file.h"

#include <array>
#include <cstring>
#include <string>

namespace ceilpose {
namespace {

uint32_t be32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}
uint32_t be16(const uint8_t* p) { return (uint32_t{p[0]} << 8) | uint32_t{p[1]}; }

constexpr std::array<uint8_t, 8> kPngSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

bool is_chunk_type(const uint8_t* p) {
  for (int k = 0; k < 4; ++k) {
    const bool letter = (p[k] >= 'A' && p[k] <= 'Z') || (p[k] >= 'a' && p[k] <= 'z');
    if (!letter) return false;
  }
  return true;
}

std::string chunk_name(const uint8_t* p) {
  return std::string(reinterpret_cast<const char*>(p), 4);
}

int png_channels(int colour_type) {
  switch (colour_type) {
    case 0:
      return 1;
    case 2:
      return 3;
    case 3:
      return 3;
    case 4:
      return 2;
    case 6:
      return 4;
    default:
      return 0;
  }
}

// PNG file layout (ISO/IEC 15948 §5): 8-byte signature, then chunks of
// length (4, big-endian) + type (4) + data (length) + CRC (4); IHDR first,
// IEND last. A file cut anywhere leaves either a chunk that overruns the end
// or no IEND.
Result<FrameFileInfo> inspect_png(const uint8_t* data, size_t size) {
  size_t pos = kPngSignature.size();
  FrameFileInfo info;
  info.encoding = FrameEncoding::kPng;
  bool seen_ihdr = false;
  bool seen_idat = false;
  while (true) {
    if (pos == size) {
      return make_error("truncated PNG: no IEND chunk (file ends after " + std::to_string(size) +
                        " bytes)");
    }
    if (size - pos < 12) {
      return make_error("truncated PNG: chunk at byte " + std::to_string(pos) +
                        " is cut off (file is " + std::to_string(size) + " bytes)");
    }
    const uint32_t length = be32(data + pos);
    const uint8_t* type = data + pos + 4;
    if (!is_chunk_type(type)) {
      return make_error("corrupt PNG: invalid chunk type at byte " + std::to_string(pos + 4));
    }
    if (length > 0x7fffffffu || length > size - pos - 12) {
      return make_error("truncated PNG: chunk " + chunk_name(type) + " at byte " +
                        std::to_string(pos) + " needs " + std::to_string(length + 12ull) +
                        " bytes, file has " + std::to_string(size - pos) + " left");
    }
    const uint8_t* body = data + pos + 8;
    if (!seen_ihdr) {
      if (std::memcmp(type, "IHDR", 4) != 0 || length != 13) {
        return make_error("corrupt PNG: first chunk is " + chunk_name(type) + ", not IHDR");
      }
      seen_ihdr = true;
      info.width = static_cast<int>(be32(body) & 0x7fffffffu);
      info.height = static_cast<int>(be32(body + 4) & 0x7fffffffu);
      info.bit_depth = body[8];
      info.png_colour_type = body[9];
      info.channels = png_channels(body[9]);
      if (info.channels == 0) {
        return make_error("corrupt PNG: invalid colour type " + std::to_string(body[9]));
      }
    } else if (std::memcmp(type, "IDAT", 4) == 0) {
      seen_idat = true;
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      if (!seen_idat) return make_error("corrupt PNG: IEND before any IDAT chunk");
      return info;
    }
    pos += 12 + static_cast<size_t>(length);
  }
}

bool is_sof(uint8_t m) { return m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc; }

// JPEG layout (ITU T.81 Annex B): SOI, marker segments (FF xx + 16-bit
// length), a frame header SOFn giving precision and size, the scan(s), EOI.
// The header segments are walked up to the first scan; the entropy-coded
// data is not parsed, so completeness is the EOI at the end (cameras may pad
// MJPEG buffers with zeros after it).
Result<FrameFileInfo> inspect_jpeg(const uint8_t* data, size_t size) {
  FrameFileInfo info;
  info.encoding = FrameEncoding::kJpeg;
  bool seen_sof = false;
  size_t pos = 2;
  while (true) {
    if (size - pos < 2) {
      return make_error("truncated JPEG: header ends at byte " + std::to_string(size));
    }
    if (data[pos] != 0xff) {
      return make_error("corrupt JPEG: expected a marker at byte " + std::to_string(pos));
    }
    while (pos + 1 < size && data[pos + 1] == 0xff) ++pos;  // fill bytes
    if (size - pos < 2)
      return make_error("truncated JPEG: header ends at byte " + std::to_string(size));
    const uint8_t marker = data[pos + 1];
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) {
      pos += 2;
      continue;
    }
    if (marker == 0xd9) return make_error("corrupt JPEG: EOI before any scan");
    if (size - pos < 4)
      return make_error("truncated JPEG: header ends at byte " + std::to_string(size));
    const uint32_t length = be16(data + pos + 2);
    if (length < 2 || length > size - pos - 2) {
      return make_error("truncated JPEG: segment at byte " + std::to_string(pos) + " needs " +
                        std::to_string(length + 2) + " bytes, file has " +
                        std::to_string(size - pos) + " left");
    }
    if (is_sof(marker)) {
      if (length < 8)
        return make_error("corrupt JPEG: short frame header at byte " + std::to_string(pos));
      info.bit_depth = data[pos + 4];
      info.height = static_cast<int>(be16(data + pos + 5));
      info.width = static_cast<int>(be16(data + pos + 7));
      info.channels = data[pos + 9];
      seen_sof = true;
    }
    if (marker == 0xda) {
      if (!seen_sof) return make_error("corrupt JPEG: scan before the frame header");
      break;
    }
    pos += 2 + length;
  }
  size_t end = size;
  while (end > pos && data[end - 1] == 0x00) --end;
  if (end - pos < 2 || data[end - 2] != 0xff || data[end - 1] != 0xd9) {
    return make_error("truncated JPEG: no EOI marker at the end (file is " + std::to_string(size) +
                      " bytes)");
  }
  return info;
}

}  // namespace

const char* to_string(FrameEncoding e) { return e == FrameEncoding::kPng ? "PNG" : "JPEG"; }

Result<FrameFileInfo> inspect_frame_bytes(const uint8_t* data, size_t size) {
  if (size >= kPngSignature.size() &&
      std::memcmp(data, kPngSignature.data(), kPngSignature.size()) == 0) {
    return inspect_png(data, size);
  }
  if (size >= 3 && data[0] == 0xff && data[1] == 0xd8 && data[2] == 0xff) {
    return inspect_jpeg(data, size);
  }
  if (size == 0) return make_error("not an image: the file is empty");
  return make_error("not an image: no PNG or JPEG signature");
}

Result<void> check_supported_frame(const FrameFileInfo& info) {
  const std::string what = info.encoding == FrameEncoding::kPng ? "PNG" : "JPEG";
  if (info.width <= 0 || info.height <= 0) {
    return make_error("corrupt " + what + ": image size " + std::to_string(info.width) + "x" +
                      std::to_string(info.height));
  }
  // Palette PNGs store indices of 1..8 bits but decode to 8-bit RGB.
  const bool palette = info.png_colour_type == 3;
  if (info.bit_depth != 8 && !palette) {
    return make_error("unsupported bit depth " + std::to_string(info.bit_depth) + " (" + what +
                      "; 8-bit RGB or greyscale required)");
  }
  if (info.channels != 1 && info.channels != 3) {
    std::string kind = info.channels == 2 ? "greyscale with alpha"
                       : info.channels == 4
                           ? (info.encoding == FrameEncoding::kPng ? "RGBA" : "CMYK")
                           : std::to_string(info.channels) + " channels";
    return make_error("unsupported " + what + " colour type (" + kind +
                      "; 8-bit RGB or greyscale required)");
  }
  return {};
}

}  // namespace ceilpose
