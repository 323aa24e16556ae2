// Depth images and masks as PNG files (libpng): 16-bit greyscale depth images read and
// written, masks of any bit depth and colour type read, 8-bit masks written.
#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "femreg/io.h"

namespace femreg {
namespace {

// 2^28 pixels (16384 x 16384): far beyond any depth camera, and 512 MiB of 16-bit values.
constexpr double kMaxPixels = 268435456.0;

// libpng reports errors through a callback that must not return: it records the message
// and jumps back to the setjmp in the reader or writer. Only C data lives between the
// setjmp and libpng's frames, so no destructor is skipped.
struct PngContext {
  const std::string* bytes = nullptr;  // reading: the file's contents
  size_t offset = 0;
  std::string* out = nullptr;          // writing: the encoded file
  char message[256] = {0};
  jmp_buf jump;
};

void OnPngError(png_structp png, png_const_charp message) {
  auto* context = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(context->message, sizeof(context->message), "%s", message);
  std::longjmp(context->jump, 1);
}

void OnPngWarning(png_structp, png_const_charp) {}  // e.g. unknown chunks: not our concern

void ReadFromBytes(png_structp png, png_bytep data, png_size_t length) {
  auto* context = static_cast<PngContext*>(png_get_io_ptr(png));
  if (context->offset + length > context->bytes->size()) {
    png_error(png, "the file ends inside the image data (truncated)");
  }
  std::memcpy(data, context->bytes->data() + context->offset, length);
  context->offset += length;
}

void WriteToString(png_structp png, png_bytep data, png_size_t length) {
  auto* context = static_cast<PngContext*>(png_get_io_ptr(png));
  context->out->append(reinterpret_cast<const char*>(data), length);
}

void FlushNothing(png_structp) {}

Status ReadFileBytes(const std::string& path, std::string* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream os;
  os << in.rdbuf();
  *bytes = os.str();
  if (bytes->size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes->data()), 0, 8) != 0) {
    return Status::Error(path + ": not a PNG file (no PNG signature in the first 8 bytes)");
  }
  return Status::Ok();
}

// What a decoded PNG holds, and how it is converted.
struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, color_type = 0;
};

const char* ColorTypeName(int color_type) {
  switch (color_type) {
    case PNG_COLOR_TYPE_GRAY:
      return "greyscale";
    case PNG_COLOR_TYPE_GRAY_ALPHA:
      return "greyscale with alpha";
    case PNG_COLOR_TYPE_RGB:
      return "RGB";
    case PNG_COLOR_TYPE_RGB_ALPHA:
      return "RGBA";
    case PNG_COLOR_TYPE_PALETTE:
      return "palette";
  }
  return "unknown colour type";
}

// Decodes `bytes` into rows of `channels` samples of 8 or 16 bits. As a depth image
// (`depth`): only 16-bit greyscale is accepted and the samples come out in host order. As a
// mask: palettes and 1/2/4-bit grey are expanded to 8-bit samples, alpha dropped, 16-bit
// samples kept (reducing them to 8 bits would turn the labels 1..255 of a 16-bit mask into 0);
// *bytes_per_pixel then counts both bytes of each sample.
// Returns false with *error set ("what went wrong").
bool DecodePng(const std::string& bytes, bool depth, PngHeader* header, std::vector<uint8_t>* pixels,
               int* bytes_per_pixel, std::string* error) {
  PngContext context;
  context.bytes = &bytes;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &context, OnPngError, OnPngWarning);
  if (png == nullptr) {
    *error = "out of memory";
    return false;
  }
  png_infop info = png_create_info_struct(png);
  std::vector<png_bytep> rows;  // sized before the setjmp's protected code needs them
  if (info == nullptr || setjmp(context.jump)) {
    png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    *error = context.message[0] ? context.message : "cannot decode";
    return false;
  }
  png_set_read_fn(png, &context, ReadFromBytes);
  png_read_info(png, info);
  png_get_IHDR(png, info, &header->width, &header->height, &header->bit_depth,
               &header->color_type, nullptr, nullptr, nullptr);
  if (static_cast<double>(header->width) * header->height > kMaxPixels) {
    std::snprintf(context.message, sizeof(context.message), "%ux%u pixels: too large (at most 2^28)",
                  header->width, header->height);
    png_destroy_read_struct(&png, &info, nullptr);
    *error = context.message;
    return false;
  }
  if (depth) {
    if (header->color_type != PNG_COLOR_TYPE_GRAY || header->bit_depth != 16) {
      std::snprintf(context.message, sizeof(context.message),
                    "a depth image must be a 16-bit greyscale PNG; this one is %d-bit %s",
                    header->bit_depth, ColorTypeName(header->color_type));
      png_destroy_read_struct(&png, &info, nullptr);
      *error = context.message;
      return false;
    }
    png_set_swap(png);  // PNG stores 16-bit samples big-endian
  } else {
    png_set_expand(png);  // palette -> RGB, 1/2/4-bit grey -> 8 bits, tRNS -> alpha
    png_set_strip_alpha(png);
  }
  png_read_update_info(png, info);
  const size_t row_bytes = png_get_rowbytes(png, info);
  *bytes_per_pixel = static_cast<int>(row_bytes / header->width);
  pixels->resize(row_bytes * header->height);
  rows.resize(header->height);
  for (png_uint_32 y = 0; y < header->height; ++y) rows[y] = pixels->data() + y * row_bytes;
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

}  // namespace

Status ReadDepthPng(const std::string& path, RawDepthImage* image) {
  std::string bytes;
  Status status = ReadFileBytes(path, &bytes);
  if (!status.ok()) return status;
  PngHeader header;
  std::vector<uint8_t> pixels;
  int bytes_per_pixel = 0;
  std::string error;
  if (!DecodePng(bytes, /*depth=*/true, &header, &pixels, &bytes_per_pixel, &error)) {
    return Status::Error(path + ": " + error);
  }
  image->width = static_cast<int>(header.width);
  image->height = static_cast<int>(header.height);
  image->metres.clear();
  image->values.resize(static_cast<size_t>(header.width) * header.height);
  std::memcpy(image->values.data(), pixels.data(), image->values.size() * sizeof(uint16_t));
  return Status::Ok();
}

Status ReadMaskPng(const std::string& path, int width, int height, std::vector<uint8_t>* keep) {
  std::string bytes;
  Status status = ReadFileBytes(path, &bytes);
  if (!status.ok()) return status;
  PngHeader header;
  std::vector<uint8_t> pixels;
  int channels = 0;
  std::string error;
  if (!DecodePng(bytes, /*depth=*/false, &header, &pixels, &channels, &error)) {
    return Status::Error(path + ": " + error);
  }
  if (static_cast<int>(header.width) != width || static_cast<int>(header.height) != height) {
    return Status::Error(path + ": the mask is " + std::to_string(header.width) + "x" +
                         std::to_string(header.height) + " pixels, the depth image " +
                         std::to_string(width) + "x" + std::to_string(height));
  }
  keep->assign(static_cast<size_t>(width) * height, 0);
  for (size_t i = 0; i < keep->size(); ++i) {
    for (int k = 0; k < channels; ++k) {  // every byte of every sample: 8- or 16-bit
      if (pixels[i * channels + k] != 0) (*keep)[i] = 1;
    }
  }
  return Status::Ok();
}

namespace {

// Encodes rows of 8- or 16-bit greyscale samples (16-bit ones already big-endian) and
// writes the file atomically.
Status WriteGreyPng(const std::string& path, int width, int height, int bit_depth,
                    const std::vector<uint8_t>& samples) {
  std::string encoded;
  PngContext context;
  context.out = &encoded;
  const size_t row_bytes = static_cast<size_t>(width) * (bit_depth / 8);
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (int y = 0; y < height; ++y) {
    rows[static_cast<size_t>(y)] = const_cast<uint8_t*>(samples.data()) + static_cast<size_t>(y) * row_bytes;
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, OnPngError, OnPngWarning);
  if (png == nullptr) return Status::Error(path + ": out of memory");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(context.jump)) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return Status::Error(path + ": cannot encode the PNG: " + context.message);
  }
  png_set_write_fn(png, &context, WriteToString, FlushNothing);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height),
               bit_depth, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 9);
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return WriteFileAtomically(path, encoded);
}

}  // namespace

Status WriteDepthPng(const std::string& path, const RawDepthImage& image) {
  if (image.in_metres()) {
    return Status::Error(path + ": a depth image in metres cannot be written as a PNG (it "
                         "holds integer depth units: convert with a depth scale first)");
  }
  if (image.width <= 0 || image.height <= 0 ||
      image.values.size() != static_cast<size_t>(image.width) * image.height) {
    return Status::Error(path + ": a depth image of " + std::to_string(image.width) + "x" +
                         std::to_string(image.height) + " pixels needs that many values (got " +
                         std::to_string(image.values.size()) + ")");
  }
  std::vector<uint8_t> big_endian(image.values.size() * 2);  // PNG's byte order
  for (size_t i = 0; i < image.values.size(); ++i) {
    big_endian[2 * i] = static_cast<uint8_t>(image.values[i] >> 8);
    big_endian[2 * i + 1] = static_cast<uint8_t>(image.values[i] & 0xff);
  }
  return WriteGreyPng(path, image.width, image.height, 16, big_endian);
}

Status WriteMaskPng(const std::string& path, int width, int height, const std::vector<uint8_t>& keep) {
  if (width <= 0 || height <= 0 || keep.size() != static_cast<size_t>(width) * height) {
    return Status::Error(path + ": a mask of " + std::to_string(width) + "x" +
                         std::to_string(height) + " pixels needs that many flags (got " +
                         std::to_string(keep.size()) + ")");
  }
  std::vector<uint8_t> samples(keep.size());
  for (size_t i = 0; i < keep.size(); ++i) samples[i] = keep[i] ? 255 : 0;
  return WriteGreyPng(path, width, height, 8, samples);
}

}  // namespace femreg
