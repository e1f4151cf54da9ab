#include "codec/png_codec.h"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

namespace ceilpose::codec {

Result<void> decode_png(const uint8_t* data, size_t size, Image* out) {
  // libpng's simplified API reports errors in `message` instead of longjmp.
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, data, size)) {
    return make_error(std::string("corrupt PNG data (") + image.message + ")");
  }
  const auto fail = [&image](const std::string& why) {
    png_image_free(&image);
    return make_error(why);
  };
  if (image.format & PNG_FORMAT_FLAG_LINEAR)
    return fail("16-bit PNG (8-bit grey or RGB supported)");
  if (image.format & PNG_FORMAT_FLAG_ALPHA)
    return fail("PNG with an alpha channel (grey or RGB supported)");
  const bool grey = (image.format & PNG_FORMAT_FLAG_COLOR) == 0;
  image.format = grey ? PNG_FORMAT_GRAY : PNG_FORMAT_RGB;
  const int width = static_cast<int>(image.width);
  const int height = static_cast<int>(image.height);
  try {
    out->resize(width, height, grey ? PixelFormat::kGray8 : PixelFormat::kRgb24);
  } catch (const std::bad_alloc&) {
    return fail("not enough memory for a " + std::to_string(width) + "x" + std::to_string(height) +
                " image");
  }
  if (!png_image_finish_read(&image, nullptr, out->data(), out->stride_bytes(), nullptr)) {
    return make_error(std::string("corrupt PNG data (") + image.message + ")");
  }
  return {};
}

namespace {

struct PngSink {
  std::vector<uint8_t>* bytes;
  bool out_of_memory = false;
};

void append_bytes(png_structp png, png_bytep data, size_t length) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  try {
    sink->bytes->insert(sink->bytes->end(), data, data + length);
  } catch (const std::bad_alloc&) {
    sink->out_of_memory = true;
  }
  // Outside the try block: png_error longjmps, which must not cross a live
  // C++ object.
  if (sink->out_of_memory) png_error(png, "out of memory");
}

void no_flush(png_structp) {}

struct PngError {
  char message[160] = "";
};

void record_error(png_structp png, png_const_charp message) {
  auto* error = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(error->message, sizeof error->message, "%s", message);
  png_longjmp(png, 1);  // back to write_png's setjmp; libpng's own handler would print
}

void ignore_warning(png_structp, png_const_charp) {}

// Holds nothing with a destructor: a libpng error longjmps back here.
bool write_png(png_structp png, png_infop info, const ImageView& src, int zlib_level,
               PngSink* sink) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_write_fn(png, sink, append_bytes, no_flush);
  png_set_compression_level(png, zlib_level);
  const bool grey = src.format == PixelFormat::kGray8;
  png_set_IHDR(png, info, static_cast<png_uint_32>(src.width), static_cast<png_uint_32>(src.height),
               8, grey ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (src.format == PixelFormat::kBgr24) png_set_bgr(png);
  for (int y = 0; y < src.height; ++y) png_write_row(png, src.row(y));
  png_write_end(png, nullptr);
  return true;
}

}  // namespace

Result<void> encode_png(const ImageView& src, int zlib_level, std::vector<uint8_t>* out) {
  if (src.format != PixelFormat::kGray8 && src.format != PixelFormat::kRgb24 &&
      src.format != PixelFormat::kBgr24) {
    return make_error(std::string("cannot store pixel format ") + to_string(src.format) +
                      " as PNG (GREY, RGB24 or BGR24)");
  }
  if (src.empty()) return make_error("cannot encode an empty image as PNG");
  PngError error;
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, record_error, ignore_warning);
  if (png == nullptr) return make_error("cannot start the PNG encoder (out of memory)");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    return make_error("cannot start the PNG encoder (out of memory)");
  }
  out->clear();
  PngSink sink{out};
  const bool ok = write_png(png, info, src, zlib_level, &sink);
  png_destroy_write_struct(&png, &info);
  if (!ok) return make_error(std::string("PNG encoder failed (") + error.message + ")");
  return {};
}

}  // namespace ceilpose::codec
