// PCD and PLY files as PointClouds (point_cloud_io.cc): io's readers (io/pcd_reader.cc,
// io/ply_reader.cc) and the conversion to femreg::PointCloud. ReadPointCloud picks the
// format; the fuzz targets call these directly.
#ifndef FEMREG_REGISTRATION_CLOUD_FILES_H_
#define FEMREG_REGISTRATION_CLOUD_FILES_H_

#include <string>

#include "femreg/point_cloud.h"
#include "femreg/status.h"

namespace femreg {
namespace internal {

// *sensor receives the PCD VIEWPOINT (may be null).
Status ReadPcdFile(const std::string& path, PointCloud* cloud, SensorPose* sensor);
Status ReadPlyFile(const std::string& path, PointCloud* cloud);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_REGISTRATION_CLOUD_FILES_H_
