// femreg/point_cloud.h - reading, writing and preprocessing point clouds.
#ifndef FEMREG_POINT_CLOUD_H_
#define FEMREG_POINT_CLOUD_H_

#include <string>

#include "femreg/registration.h"
#include "femreg/status.h"

namespace femreg {

// Reads PCD (ASCII, binary, binary-compressed), PLY (through PCL) or plain text with
// "x y z" (optionally "x y z nx ny nz") per line. Normals are kept when present. Points
// with a NaN or infinite coordinate are dropped and counted in *nonfinite_dropped.
Status ReadPointCloud(const std::string& path, PointCloud* cloud, int* nonfinite_dropped = nullptr);

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
