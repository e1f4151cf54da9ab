#pragma once
// JPEG with libjpeg-turbo's TurboJPEG API: a recording's JPEG frames, MJPEG
// cameras and the simulator's compression. Error messages describe the
// defect; callers prefix the file or device.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "core/result.h"

namespace ceilpose::codec {

struct JpegHeader {
  int width = 0;
  int height = 0;
  bool grey = false;  // one component
  // Colour with chroma at half the resolution (4:2:0, 4:2:2, 4:4:0, 4:1:1):
  // what it decodes to is marked ImageView::chroma_halved.
  bool chroma_halved = false;
};

// One per thread: it holds the library's handles, so once the frame size
// settles a frame allocates nothing.
class JpegCodec {
 public:
  JpegCodec() = default;
  ~JpegCodec();
  JpegCodec(const JpegCodec&) = delete;
  JpegCodec& operator=(const JpegCodec&) = delete;
  JpegCodec(JpegCodec&& other) noexcept;
  JpegCodec& operator=(JpegCodec&& other) noexcept;

  Result<JpegHeader> header(const uint8_t* data, size_t size);

  // The scale denominators `decode` accepts (libjpeg-turbo scales in the DCT,
  // so a reduced decode costs less than a full one).
  static bool scale_supported(int denominator) {
    return denominator == 1 || denominator == 2 || denominator == 4 || denominator == 8;
  }

  // Decodes into `out` as `format` (kGray8, kRgb24 or kBgr24), resized to the
  // image's size divided by `scale_denominator` (rounded up). A corrupt or
  // truncated stream is an error, never a partly grey picture.
  Result<void> decode(const uint8_t* data, size_t size, PixelFormat format, Image* out,
                      int scale_denominator = 1);

  // As decode, into an image whose size and format are fixed (a capture
  // buffer): a stream of any other size is refused and nothing is allocated.
  Result<void> decode_fixed(const uint8_t* data, size_t size, Image* out);

  // Encodes kGray8 (one component), kRgb24 or kBgr24 (4:2:0 chroma, as
  // cameras and OpenCV do) at `quality` 1-100 into `out`.
  Result<void> encode(const ImageView& src, int quality, std::vector<uint8_t>* out);

 private:
  Result<void> decode_to(const uint8_t* data, size_t size, const JpegHeader& header,
                         PixelFormat format, int scale_denominator, Image* out);
  void* decompressor_ = nullptr;  // tjhandle
  void* compressor_ = nullptr;    // tjhandle
};

}  // namespace ceilpose::codec
