// femreg synth --depth-png: a sequence's clouds as the 16-bit depth images its camera
// would have stored.
#include <algorithm>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "femreg/point_cloud.h"
#include "femreg/synth.h"

namespace femreg {

Status WriteDepthFrames(const std::string& clouds_dir, const CameraOptions& camera,
                        double depth_scale, const std::string& depth_dir,
                        DepthFramesReport* report) {
  namespace fs = std::filesystem;
  *report = DepthFramesReport();
  if (!(depth_scale > 0)) {
    return Status::Error("depth_scale must be > 0 (got " + std::to_string(depth_scale) + ")");
  }
  std::string why;
  if (!camera.IsValid(&why)) return Status::Error("camera: " + why);
  std::error_code ec;
  std::vector<fs::path> clouds;
  for (const auto& entry : fs::directory_iterator(clouds_dir, ec)) {
    if (entry.is_regular_file() && entry.path().extension() == ".pcd") clouds.push_back(entry.path());
  }
  if (ec) return Status::Error(clouds_dir + ": " + ec.message());
  if (clouds.empty()) return Status::Error(clouds_dir + ": no .pcd clouds to render");
  std::sort(clouds.begin(), clouds.end());
  fs::create_directories(depth_dir, ec);
  if (ec) return Status::Error(depth_dir + ": cannot create the folder: " + ec.message());
  for (const fs::path& path : clouds) {
    PointCloud cloud;
    Status status = ReadPointCloud(path.string(), &cloud);
    if (!status.ok()) return status;
    int dropped = 0;
    const RawDepthImage image = CloudToDepthImage(cloud, camera, depth_scale, &dropped);
    const fs::path png = fs::path(depth_dir) / (path.stem().string() + ".png");
    status = WriteDepthPng(png.string(), image);
    if (!status.ok()) return status;
    ++report->frames;
    report->points += cloud.size();
    report->dropped += dropped;
  }
  return Status::Ok();
}

}  // namespace femreg
