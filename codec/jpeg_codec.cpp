#include "codec/jpeg_codec.h"

#include <turbojpeg.h>

#include <climits>
#include <new>
#include <string>
#include <utility>

namespace ceilpose::codec {

namespace {

std::string library_error(void* handle) { return tjGetErrorStr2(static_cast<tjhandle>(handle)); }

int turbo_format(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGray8:
      return TJPF_GRAY;
    case PixelFormat::kRgb24:
      return TJPF_RGB;
    case PixelFormat::kBgr24:
      return TJPF_BGR;
    default:
      return -1;
  }
}

int scaled(int size, int denominator) { return (size + denominator - 1) / denominator; }

}  // namespace

JpegCodec::~JpegCodec() {
  if (decompressor_ != nullptr) tjDestroy(static_cast<tjhandle>(decompressor_));
  if (compressor_ != nullptr) tjDestroy(static_cast<tjhandle>(compressor_));
}

JpegCodec::JpegCodec(JpegCodec&& other) noexcept
    : decompressor_(std::exchange(other.decompressor_, nullptr)),
      compressor_(std::exchange(other.compressor_, nullptr)) {}

JpegCodec& JpegCodec::operator=(JpegCodec&& other) noexcept {
  std::swap(decompressor_, other.decompressor_);
  std::swap(compressor_, other.compressor_);
  return *this;
}

Result<JpegHeader> JpegCodec::header(const uint8_t* data, size_t size) {
  if (decompressor_ == nullptr) decompressor_ = tjInitDecompress();
  if (decompressor_ == nullptr) return make_error("cannot start the JPEG decoder (out of memory)");
  if (size < 4 || data[0] != 0xFF || data[1] != 0xD8)
    return make_error("not JPEG data (no start-of-image marker)");
  if (size > ULONG_MAX) return make_error("JPEG data too large");
  int width = 0, height = 0, subsampling = 0, colourspace = 0;
  if (tjDecompressHeader3(static_cast<tjhandle>(decompressor_), data,
                          static_cast<unsigned long>(size), &width, &height, &subsampling,
                          &colourspace) != 0) {
    return make_error("corrupt JPEG data (" + library_error(decompressor_) + ")");
  }
  const bool grey = colourspace == TJCS_GRAY;
  return JpegHeader{width, height, grey, !grey && subsampling != TJSAMP_444};
}

Result<void> JpegCodec::decode(const uint8_t* data, size_t size, PixelFormat format, Image* out,
                               int scale_denominator) {
  if (!scale_supported(scale_denominator)) {
    return make_error("JPEG scale 1/" + std::to_string(scale_denominator) +
                      " not supported (1, 2, 4 or 8)");
  }
  auto head = header(data, size);
  if (!head) return head.error();
  try {
    out->resize(scaled(head->width, scale_denominator), scaled(head->height, scale_denominator),
                format);
  } catch (const std::bad_alloc&) {
    return make_error("not enough memory for a " + std::to_string(head->width) + "x" +
                      std::to_string(head->height) + " image");
  }
  return decode_to(data, size, *head, format, scale_denominator, out);
}

Result<void> JpegCodec::decode_fixed(const uint8_t* data, size_t size, Image* out) {
  auto head = header(data, size);
  if (!head) return head.error();
  if (head->width != out->width() || head->height != out->height()) {
    return make_error("JPEG of " + std::to_string(head->width) + "x" +
                      std::to_string(head->height) + " where " + std::to_string(out->width()) +
                      "x" + std::to_string(out->height()) + " was negotiated");
  }
  return decode_to(data, size, *head, out->format(), 1, out);
}

Result<void> JpegCodec::decode_to(const uint8_t* data, size_t size, const JpegHeader& header,
                                  PixelFormat format, int scale_denominator, Image* out) {
  const int pixel_format = turbo_format(format);
  if (pixel_format < 0) {
    return make_error(std::string("cannot decode JPEG into ") + to_string(format) +
                      " (GREY, RGB24 or BGR24)");
  }
  // TurboJPEG picks the DCT scale that gives at most this size.
  const int width = scaled(header.width, scale_denominator);
  const int height = scaled(header.height, scale_denominator);
  if (tjDecompress2(static_cast<tjhandle>(decompressor_), data, static_cast<unsigned long>(size),
                    out->data(), width, out->stride_bytes(), height, pixel_format,
                    TJFLAG_STOPONWARNING) != 0) {
    return make_error("corrupt JPEG data (" + library_error(decompressor_) + ")");
  }
  out->set_chroma_halved(header.chroma_halved);
  return {};
}

Result<void> JpegCodec::encode(const ImageView& src, int quality, std::vector<uint8_t>* out) {
  const int pixel_format = turbo_format(src.format);
  if (pixel_format < 0) {
    return make_error(std::string("cannot store pixel format ") + to_string(src.format) +
                      " as JPEG (GREY, RGB24 or BGR24)");
  }
  if (src.empty()) return make_error("cannot encode an empty image as JPEG");
  if (quality < 1 || quality > 100) {
    return make_error("JPEG quality " + std::to_string(quality) + " outside 1-100");
  }
  if (compressor_ == nullptr) compressor_ = tjInitCompress();
  if (compressor_ == nullptr) return make_error("cannot start the JPEG encoder (out of memory)");
  const int subsampling = src.format == PixelFormat::kGray8 ? TJSAMP_GRAY : TJSAMP_420;
  const unsigned long bound = tjBufSize(src.width, src.height, subsampling);
  if (bound == static_cast<unsigned long>(-1)) return make_error("image too large for JPEG");
  try {
    out->resize(bound);
  } catch (const std::bad_alloc&) {
    return make_error("not enough memory for the JPEG encoder's output");
  }
  // Into our buffer, sized for the worst case: the library never reallocates.
  unsigned char* buffer = out->data();
  unsigned long written = bound;
  if (tjCompress2(static_cast<tjhandle>(compressor_), src.data, src.width, src.stride_bytes,
                  src.height, pixel_format, &buffer, &written, subsampling, quality,
                  TJFLAG_NOREALLOC) != 0) {
    out->clear();
    return make_error("JPEG encoder failed (" + library_error(compressor_) + ")");
  }
  out->resize(written);
  return {};
}

}  // namespace ceilpose::codec
