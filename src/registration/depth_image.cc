// Depth images as frames: 16-bit PNGs read and written with libpng, back-projected through
// the scene's camera; masks; the projection of a cloud into a depth image (for synth).
#include <png.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/io.h"
#include "femreg/point_cloud.h"

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

bool DepthImageOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(depth_scale > 0) || !std::isfinite(depth_scale)) {
    os << "depth_scale must be > 0 (got " << depth_scale << ")";
  } else if (!(min_depth >= 0) || !std::isfinite(min_depth)) {
    os << "min_depth must be >= 0 (got " << min_depth << ")";
  } else if (!(max_depth >= 0) || !std::isfinite(max_depth) ||
             (max_depth > 0 && max_depth < min_depth)) {
    os << "max_depth must be 0 (no limit) or >= min_depth (got " << max_depth << ")";
  } else if (pixel_stride < 1) {
    os << "pixel_stride must be >= 1 (got " << pixel_stride << ")";
  } else {
    return true;
  }
  if (error != nullptr) *error = os.str();
  return false;
}

Eigen::Matrix3d CameraRotation(const CameraOptions& c) {
  // z along the optical axis, image y (pointing down) against the part of `up` orthogonal
  // to it, x = y cross z. The virtual camera (DepthSensor) renders through this frame too.
  Eigen::Vector3d z = c.target - c.position;
  if (z.norm() <= 0) z = Eigen::Vector3d::UnitZ();
  z.normalize();
  Eigen::Vector3d y = -(c.up - c.up.dot(z) * z);
  if (y.norm() < 1e-9) y = z.unitOrthogonal();
  y.normalize();
  const Eigen::Vector3d x = y.cross(z);
  Eigen::Matrix3d r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

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

Status BackProjectDepth(const RawDepthImage& image, const CameraOptions& camera,
                        const DepthImageOptions& options, const std::vector<uint8_t>* keep,
                        PointCloud* cloud, SensorPose* sensor) {
  std::string why;
  if (!options.IsValid(&why)) return Status::Error("depth image options: " + why);
  if (!camera.IsValid(&why)) return Status::Error("camera: " + why);
  if (image.width != camera.width || image.height != camera.height) {
    return Status::Error("the depth image is " + std::to_string(image.width) + "x" +
                         std::to_string(image.height) + " pixels, the camera " +
                         std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                         " (registration.camera width and height)");
  }
  const size_t n = static_cast<size_t>(image.width) * image.height;
  if (image.values.size() != n || (keep != nullptr && keep->size() != n)) {
    return Status::Error("the depth image's or the mask's size does not match its width and height");
  }
  const Eigen::Matrix3d r = CameraRotation(camera);
  const Eigen::Matrix3d rt = r.transpose();
  const double max_depth = options.max_depth > 0 ? options.max_depth
                                                 : std::numeric_limits<double>::infinity();
  const int stride = options.pixel_stride;
  size_t count = 0;
  for (int v = 0; v < image.height; v += stride) {
    for (int u = 0; u < image.width; u += stride) {
      const size_t i = static_cast<size_t>(v) * image.width + u;
      if (image.values[i] == 0 || (keep != nullptr && !(*keep)[i])) continue;
      const double z = image.values[i] * options.depth_scale;
      if (z >= options.min_depth && z <= max_depth) ++count;
    }
  }
  cloud->points.resize(static_cast<Eigen::Index>(count), 3);
  cloud->normals.resize(0, 3);
  cloud->labels.resize(0);
  Eigen::Index row = 0;
  for (int v = 0; v < image.height; v += stride) {
    for (int u = 0; u < image.width; u += stride) {
      const size_t i = static_cast<size_t>(v) * image.width + u;
      if (image.values[i] == 0 || (keep != nullptr && !(*keep)[i])) continue;
      const double z = image.values[i] * options.depth_scale;
      if (!(z >= options.min_depth && z <= max_depth)) continue;
      const Eigen::Vector3d ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      cloud->points.row(row++) = (camera.position + rt * (z * ray)).transpose();
    }
  }
  if (sensor != nullptr) {
    sensor->known = true;
    sensor->origin = camera.position;
    sensor->orientation = Eigen::Quaterniond(rt).normalized();  // camera to scene frame
  }
  return Status::Ok();
}

Status ReadDepthFrame(const std::string& path, const CameraOptions& camera,
                      const DepthImageOptions& options, PointCloud* cloud, SensorPose* sensor) {
  std::string why;
  if (!options.IsValid(&why)) return Status::Error(path + ": depth image options: " + why);
  RawDepthImage image;
  Status status = ReadDepthPng(path, &image);
  if (!status.ok()) return status;
  std::vector<uint8_t> keep;
  if (!options.mask_dir.empty()) {
    const std::string mask =
        (std::filesystem::path(options.mask_dir) / std::filesystem::path(path).filename()).string();
    status = ReadMaskPng(mask, image.width, image.height, &keep);
    if (!status.ok()) return Status::Error(path + ": mask: " + status.message());
  }
  status = BackProjectDepth(image, camera, options, keep.empty() ? nullptr : &keep, cloud, sensor);
  if (!status.ok()) return Status::Error(path + ": " + status.message());
  return Status::Ok();
}

RawDepthImage CloudToDepthImage(const PointCloud& cloud, const CameraOptions& camera,
                                double depth_scale, int* dropped) {
  RawDepthImage image;
  image.width = camera.width;
  image.height = camera.height;
  image.values.assign(static_cast<size_t>(std::max(0, camera.width)) * std::max(0, camera.height), 0);
  const Eigen::Matrix3d r = CameraRotation(camera);
  int left_out = 0;
  for (int i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d q = r * (cloud.points.row(i).transpose() - camera.position);
    const long units = q.z() > 0 ? std::lround(q.z() / depth_scale) : 0;
    if (!(q.z() > 0) || !q.allFinite() || units < 1 || units > 65535) {
      ++left_out;
      continue;
    }
    const long u = std::lround(camera.fx * q.x() / q.z() + camera.cx);
    const long v = std::lround(camera.fy * q.y() / q.z() + camera.cy);
    if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) {
      ++left_out;
      continue;
    }
    uint16_t& pixel = image.values[static_cast<size_t>(v) * camera.width + static_cast<size_t>(u)];
    if (pixel != 0) ++left_out;  // two points on one pixel: the nearer one is seen
    if (pixel == 0 || units < pixel) pixel = static_cast<uint16_t>(units);
  }
  if (dropped != nullptr) *dropped = left_out;
  return image;
}

Status ReadFrame(const std::string& path, const CameraOptions& camera,
                 const DepthImageOptions& depth, PointCloud* cloud, int* nonfinite_dropped,
                 SensorPose* sensor) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
  if (ext == ".png") {
    if (nonfinite_dropped != nullptr) *nonfinite_dropped = 0;
    return ReadDepthFrame(path, camera, depth, cloud, sensor);
  }
  return ReadPointCloud(path, cloud, nonfinite_dropped, sensor);
}

}  // namespace femreg
