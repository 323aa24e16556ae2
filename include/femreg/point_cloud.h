// femreg/point_cloud.h - reading, writing and preprocessing point clouds.
#ifndef FEMREG_POINT_CLOUD_H_
#define FEMREG_POINT_CLOUD_H_

#include <Eigen/Geometry>
#include <string>

#include "femreg/registration.h"
#include "femreg/status.h"

namespace femreg {

// Where the sensor was when it took a cloud, as a PCD file's VIEWPOINT line gives it
// ("VIEWPOINT tx ty tz qw qx qy qz"): the camera centre and its orientation, in the
// cloud's frame.
struct SensorPose {
  bool known = false;  // false: the file has no VIEWPOINT line (PLY, text, or older PCD)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // normalized
};

// Reads PCD (ASCII, binary, binary_compressed; fields x y z of type F required, normal_x
// normal_y normal_z and label used when present), PLY (ASCII or binary, vertex x y z and
// nx ny nz or normal_x normal_y normal_z) or plain text with "x y z" (optionally
// "x y z nx ny nz") per line. Normals are kept when present. Points with a NaN or infinite
// coordinate are dropped and counted in *nonfinite_dropped. Every count and size in a
// header is checked against the file's length before anything is allocated; errors name
// the file and the line (text) or byte offset (binary). *sensor, when given, receives the
// PCD VIEWPOINT.
Status ReadPointCloud(const std::string& path, PointCloud* cloud, int* nonfinite_dropped = nullptr,
                      SensorPose* sensor = nullptr);

// Writes a binary PCD (with normals when the cloud has them), atomically.
Status WritePointCloud(const std::string& path, const PointCloud& cloud);

// Drops non-finite points (counted), then crops, voxel-downsamples, removes statistical
// outliers and estimates normals as the options ask (oriented towards `viewpoint`, the
// camera centre).
void PreprocessPointCloud(const PreprocessOptions& options, PointCloud* cloud,
                          int* nonfinite_dropped = nullptr,
                          const Eigen::Vector3d& viewpoint = Eigen::Vector3d::Zero());

// Removes points with a non-finite coordinate (or normal); returns how many.
int DropNonFinite(PointCloud* cloud);

}  // namespace femreg

#endif  // FEMREG_POINT_CLOUD_H_
