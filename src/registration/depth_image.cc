// Depth images as frames: back-projected through the scene's camera, masked, read by their
// file type (PNG, NumPy: femreg/camera_io.h); the projection of a cloud into a depth image
// (for synth); the frames of a recording (a folder, a pattern, a TUM RGB-D list).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "io/io_internal.h"

namespace femreg {
namespace {

std::string Extension(const std::string& path) { return internal::LowercaseExtension(path); }

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
  const bool in_metres = image.in_metres();
  if ((in_metres ? image.metres.size() : image.values.size()) != n ||
      (in_metres && !image.values.empty()) || (keep != nullptr && keep->size() != n)) {
    return Status::Error("the depth image's or the mask's size does not match its width and height");
  }
  // Pixel i's depth in metres; 0 = no return (0 units; 0, negative or not finite metres).
  auto depth_of = [&](size_t i) -> double {
    if (!in_metres) return image.values[i] * options.depth_scale;
    const double z = image.metres[i];
    return std::isfinite(z) && z > 0 ? z : 0.0;
  };
  const Eigen::Matrix3d r = CameraRotation(camera);
  const Eigen::Matrix3d rt = r.transpose();
  const double max_depth = options.max_depth > 0 ? options.max_depth
                                                 : std::numeric_limits<double>::infinity();
  const int stride = options.pixel_stride;
  size_t count = 0;
  for (int v = 0; v < image.height; v += stride) {
    for (int u = 0; u < image.width; u += stride) {
      const size_t i = static_cast<size_t>(v) * image.width + u;
      if (keep != nullptr && !(*keep)[i]) continue;
      const double z = depth_of(i);
      if (z > 0 && z >= options.min_depth && z <= max_depth) ++count;
    }
  }
  cloud->points.resize(static_cast<Eigen::Index>(count), 3);
  cloud->normals.resize(0, 3);
  cloud->labels.resize(0);
  Eigen::Index row = 0;
  for (int v = 0; v < image.height; v += stride) {
    for (int u = 0; u < image.width; u += stride) {
      const size_t i = static_cast<size_t>(v) * image.width + u;
      if (keep != nullptr && !(*keep)[i]) continue;
      const double z = depth_of(i);
      if (!(z > 0 && z >= options.min_depth && z <= max_depth)) continue;
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
  Status status = ReadDepthImageFile(path, &image);
  if (!status.ok()) return status;
  std::vector<uint8_t> keep;
  if (!options.mask_dir.empty()) {
    const std::string mask = MaskPathFor(options.mask_dir, path);
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
  if (IsDepthImageFile(path)) {
    if (nonfinite_dropped != nullptr) *nonfinite_dropped = 0;
    return ReadDepthFrame(path, camera, depth, cloud, sensor);
  }
  return ReadPointCloud(path, cloud, nonfinite_dropped, sensor);
}

bool IsDepthImageFile(const std::string& path) {
  const std::string ext = Extension(path);
  return ext == ".png" || ext == ".npy";
}

std::string MaskPathFor(const std::string& mask_dir, const std::string& frame) {
  // A PNG frame's mask has its file name (as it always had, whatever the case of ".png");
  // another frame's, its stem and ".png": masks are PNGs.
  const std::filesystem::path name = std::filesystem::path(frame).filename();
  const std::filesystem::path mask =
      Extension(frame) == ".png" ? name : std::filesystem::path(name.stem().string() + ".png");
  return (std::filesystem::path(mask_dir) / mask).string();
}

PinholeIntrinsics IntrinsicsOf(const CameraOptions& camera) {
  PinholeIntrinsics k;
  k.fx = camera.fx;
  k.fy = camera.fy;
  k.cx = camera.cx;
  k.cy = camera.cy;
  k.width = camera.width;
  k.height = camera.height;
  return k;
}

void SetIntrinsics(const PinholeIntrinsics& k, CameraOptions* camera) {
  camera->fx = k.fx;
  camera->fy = k.fy;
  camera->cx = k.cx;
  camera->cy = k.cy;
  camera->width = k.width;
  camera->height = k.height;
}

Status ReadCameraIntrinsics(const std::string& path, CameraOptions* camera) {
  PinholeIntrinsics k;
  if (LooksLikeJsonFile(path)) {
    Status status = ReadOpen3dIntrinsics(path, &k);
    if (status.ok()) SetIntrinsics(k, camera);
    return status;
  }
  Status status = ReadMatrixIntrinsics(path, &k);
  if (!status.ok()) return status;
  k.width = camera->width;  // a matrix holds no image size
  k.height = camera->height;
  SetIntrinsics(k, camera);
  return Status::Ok();
}

Status WriteCameraIntrinsics(const std::string& path, const CameraOptions& camera) {
  return WriteOpen3dIntrinsics(path, IntrinsicsOf(camera));
}

Status ListFrameFiles(const std::string& path, FrameFiles* frames) {
  *frames = FrameFiles();
  std::error_code ec;
  std::string list;
  if (std::filesystem::is_directory(path, ec)) {
    list = FindTumList(path);
  } else if (std::filesystem::is_regular_file(path, ec) && LooksLikeTumList(path)) {
    list = path;
  }
  if (!list.empty()) {
    TumSequence sequence;
    Status status = ReadTumSequence(list, &sequence);
    if (!status.ok()) return status;
    frames->tum_list = sequence.list;
    frames->depth_scale = kTumDepthScale;
    for (const TumFrame& f : sequence.frames) {
      frames->files.push_back(f.depth);
      frames->times.push_back(f.time);
    }
    return Status::Ok();
  }
  return ListFiles(path, {".pcd", ".ply", ".xyz", ".txt", ".png", ".npy"}, &frames->files);
}

}  // namespace femreg
