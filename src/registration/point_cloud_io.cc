// Point clouds: the reader front end (PCD, PLY and text read by io/pcd_reader.cc,
// io/ply_reader.cc and io/xyz_reader.cc, converted here), the binary PCD writer (PCL) and
// the filters (PCL).
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/crop_box.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "femreg/point_cloud.h"
#include "io/io_internal.h"
#include "io/ply_reader.h"
#include "registration/cloud_files.h"
#include "registration/cloud_subset.h"

namespace femreg {

namespace {

using PclCloud = pcl::PointCloud<pcl::PointNormal>;

// Labels ride through the PCL filters in the (otherwise unused) curvature field.
void FromPcl(const PclCloud& in, bool with_normals, PointCloud* out, bool with_labels = false) {
  out->points.resize(static_cast<Eigen::Index>(in.size()), 3);
  out->normals.resize(with_normals ? static_cast<Eigen::Index>(in.size()) : 0, 3);
  out->labels.resize(with_labels ? static_cast<Eigen::Index>(in.size()) : 0);
  for (size_t i = 0; i < in.size(); ++i) {
    const auto& p = in[i];
    const auto r = static_cast<Eigen::Index>(i);
    out->points.row(r) << p.x, p.y, p.z;
    if (with_normals) out->normals.row(r) << p.normal_x, p.normal_y, p.normal_z;
    if (with_labels) out->labels(r) = static_cast<int>(std::lround(p.curvature));
  }
}

PclCloud::Ptr ToPcl(const PointCloud& in) {
  PclCloud::Ptr out(new PclCloud);
  out->resize(static_cast<size_t>(in.size()));
  for (int i = 0; i < in.size(); ++i) {
    auto& p = (*out)[static_cast<size_t>(i)];
    p.x = static_cast<float>(in.points(i, 0));
    p.y = static_cast<float>(in.points(i, 1));
    p.z = static_cast<float>(in.points(i, 2));
    if (in.has_normals()) {
      p.normal_x = static_cast<float>(in.normals(i, 0));
      p.normal_y = static_cast<float>(in.normals(i, 1));
      p.normal_z = static_cast<float>(in.normals(i, 2));
    } else {
      p.normal_x = p.normal_y = p.normal_z = 0.0f;
    }
    p.curvature = in.has_labels() ? static_cast<float>(in.labels(i)) : 0.0f;
  }
  out->width = static_cast<uint32_t>(out->size());
  out->height = 1;
  out->is_dense = true;
  return out;
}

// A cloud as io's readers found it, as a PointCloud.
void Store(const internal::RawCloud& raw, PointCloud* cloud) {
  const Eigen::Index n = static_cast<Eigen::Index>(raw.xyz.size() / 3);
  cloud->points.resize(n, 3);
  cloud->normals.resize(raw.normals.empty() ? 0 : n, 3);
  cloud->labels.resize(raw.labels.empty() ? 0 : n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      cloud->points(i, k) = raw.xyz[3 * i + k];
      if (!raw.normals.empty()) cloud->normals(i, k) = raw.normals[3 * i + k];
    }
    if (!raw.labels.empty()) cloud->labels(i) = raw.labels[i];
  }
}

}  // namespace

namespace internal {

Status ReadPcdFile(const std::string& path, PointCloud* cloud, SensorPose* sensor) {
  RawCloud raw;
  const Status status = ReadPcdCloud(path, &raw);
  if (!status.ok()) return status;
  Store(raw, cloud);
  if (sensor != nullptr) {
    sensor->known = raw.viewpoint_known;
    sensor->origin = Eigen::Vector3d(raw.origin[0], raw.origin[1], raw.origin[2]);
    sensor->orientation = Eigen::Quaterniond(raw.orientation[0], raw.orientation[1],
                                             raw.orientation[2], raw.orientation[3]);
  }
  return Status::Ok();
}

Status ReadPlyFile(const std::string& path, PointCloud* cloud) {
  RawCloud raw;
  const Status status = ReadPlyCloud(path, &raw);
  if (!status.ok()) return status;
  Store(raw, cloud);
  return Status::Ok();
}

}  // namespace internal

int KeepPoints(const std::function<bool(int)>& keep, PointCloud* cloud) {
  const bool normals = cloud->has_normals();
  const bool labels = cloud->has_labels();
  int kept = 0;
  for (int i = 0; i < cloud->size(); ++i) {
    if (!keep(i)) continue;
    if (kept != i) {
      cloud->points.row(kept) = cloud->points.row(i);
      if (normals) cloud->normals.row(kept) = cloud->normals.row(i);
      if (labels) cloud->labels(kept) = cloud->labels(i);
    }
    ++kept;
  }
  const int dropped = cloud->size() - kept;
  cloud->points.conservativeResize(kept, 3);
  if (normals) cloud->normals.conservativeResize(kept, 3);
  if (labels) cloud->labels.conservativeResize(kept);
  return dropped;
}

int DropNonFinite(PointCloud* cloud) {
  const bool normals = cloud->has_normals();
  return KeepPoints([&](int i) {
    return cloud->points.row(i).allFinite() && (!normals || cloud->normals.row(i).allFinite());
  }, cloud);
}

namespace {

Status ReadPointCloudUnchecked(const std::string& path, PointCloud* cloud, int* nonfinite_dropped,
                               SensorPose* sensor) {
  // A PCD or PLY file always has a header: with no byte at all it was cut off or never
  // written (a text cloud with no line is a cloud without points).
  std::error_code ec;
  const std::string extension = internal::LowercaseExtension(path);
  if ((extension == ".pcd" || extension == ".ply") && std::filesystem::is_regular_file(path, ec) &&
      std::filesystem::file_size(path, ec) == 0 && !ec) {
    return Status::Error(path + ": the file is empty (0 bytes): a " + extension.substr(1) +
                         " file starts with its header");
  }
  internal::CloudFileFormat format;
  Status status = internal::DetectCloudFormat(path, &format);
  if (!status.ok()) return status;
  if (sensor != nullptr) *sensor = SensorPose();
  if (format == internal::CloudFileFormat::kPly) {
    status = internal::ReadPlyFile(path, cloud);
  } else if (format == internal::CloudFileFormat::kPcd) {
    status = internal::ReadPcdFile(path, cloud, sensor);
  } else {
    internal::RawCloud raw;
    status = internal::ReadXyzCloud(path, &raw);
    if (status.ok()) Store(raw, cloud);
  }
  if (!status.ok()) return status;
  const int dropped = DropNonFinite(cloud);
  if (nonfinite_dropped) *nonfinite_dropped = dropped;
  return Status::Ok();
}

}  // namespace

Status ReadPointCloud(const std::string& path, PointCloud* cloud, int* nonfinite_dropped,
                      SensorPose* sensor) {
  // The readers check every count against the file first; this catches a file that is
  // valid but larger than memory.
  try {
    PointCloud read;
    Status status = ReadPointCloudUnchecked(path, &read, nonfinite_dropped, sensor);
    if (status.ok()) *cloud = std::move(read);
    return status;
  } catch (const std::bad_alloc&) {
    return Status::Error(path + ": out of memory while reading the point cloud");
  } catch (const std::length_error& e) {
    return Status::Error(path + ": out of memory while reading the point cloud (" + e.what() + ")");
  }
}

Status WritePointCloud(const std::string& path, const PointCloud& cloud) {
  // Written as binary PCD only: a file named otherwise would hold what its name does not say.
  if (internal::LowercaseExtension(path) != ".pcd") {
    return Status::Error(path + ": point clouds are written as PCD (binary); name the file .pcd");
  }
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  const std::string tmp = path + ".tmp";
  PclCloud::Ptr pc = ToPcl(cloud);
  int rc = -1;
  try {  // PCL throws when it cannot open or parse the file
    if (cloud.has_labels()) {
      pcl::PointCloud<pcl::PointXYZLNormal> labelled;
      pcl::copyPointCloud(*pc, labelled);
      for (size_t i = 0; i < labelled.size(); ++i) {
        labelled[i].label = static_cast<uint32_t>(cloud.labels(static_cast<Eigen::Index>(i)));
      }
      rc = pcl::io::savePCDFileBinary(tmp, labelled);
    } else if (cloud.has_normals()) {
      rc = pcl::io::savePCDFileBinary(tmp, *pc);
    } else {
      pcl::PointCloud<pcl::PointXYZ> xyz;
      pcl::copyPointCloud(*pc, xyz);
      rc = pcl::io::savePCDFileBinary(tmp, xyz);
    }
  } catch (const std::exception&) {
    rc = -1;
  }
  if (rc < 0 || std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return Status::Error(path + ": cannot write");
  }
  return Status::Ok();
}

void PreprocessPointCloud(const PreprocessOptions& options, PointCloud* cloud,
                          int* nonfinite_dropped, const Eigen::Vector3d& viewpoint,
                          RemovedPlane* plane) {
  if (plane != nullptr) *plane = RemovedPlane();
  const int dropped = DropNonFinite(cloud);
  if (nonfinite_dropped) *nonfinite_dropped = dropped;
  const bool any = options.crop || options.plane_distance > 0 || options.voxel_size > 0 ||
                   options.outlier_neighbors > 0 || options.normal_neighbors > 0;
  if (!any || cloud->size() == 0) return;
  bool normals = cloud->has_normals();
  const bool labels = cloud->has_labels();
  PclCloud::Ptr pc = ToPcl(*cloud);
  if (options.crop) {
    pcl::CropBox<pcl::PointNormal> crop;
    crop.setMin(Eigen::Vector4f(options.crop_min.x(), options.crop_min.y(), options.crop_min.z(), 1));
    crop.setMax(Eigen::Vector4f(options.crop_max.x(), options.crop_max.y(), options.crop_max.z(), 1));
    crop.setInputCloud(pc);
    PclCloud::Ptr out(new PclCloud);
    crop.filter(*out);
    pc = out;
  }
  if (options.plane_distance > 0 && pc->size() >= 3) {
    // RANSAC with PCL's fixed seed: the same cloud loses the same points every run.
    pcl::SACSegmentation<pcl::PointNormal> seg;
    seg.setModelType(pcl::SACMODEL_PLANE);
    seg.setMethodType(pcl::SAC_RANSAC);
    seg.setDistanceThreshold(options.plane_distance);
    seg.setMaxIterations(options.plane_iterations);
    seg.setOptimizeCoefficients(true);
    seg.setInputCloud(pc);
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coefficients;
    seg.segment(inliers, coefficients);
    if (!inliers.indices.empty()) {
      std::vector<char> drop(pc->size(), 0);
      for (int i : inliers.indices) drop[static_cast<size_t>(i)] = 1;
      const Eigen::Vector3d n = coefficients.values.size() == 4
                                    ? Eigen::Vector3d(coefficients.values[0], coefficients.values[1],
                                                      coefficients.values[2])
                                    : Eigen::Vector3d::Zero();
      if (plane != nullptr && n.norm() > 0) {
        plane->normal = n / n.norm();
        plane->offset = -coefficients.values[3] / n.norm();
        plane->points.resize(static_cast<Eigen::Index>(inliers.indices.size()), 3);
        for (size_t k = 0; k < inliers.indices.size(); ++k) {
          const pcl::PointNormal& q = (*pc)[static_cast<size_t>(inliers.indices[k])];
          plane->points.row(static_cast<Eigen::Index>(k)) << q.x, q.y, q.z;
        }
      }
      PclCloud::Ptr out(new PclCloud);
      for (size_t i = 0; i < pc->size(); ++i) {
        if (!drop[i]) out->push_back((*pc)[i]);
      }
      pc = out;
    }
  }
  if (options.voxel_size > 0 && !pc->empty()) {
    pcl::VoxelGrid<pcl::PointNormal> grid;
    const float leaf = static_cast<float>(options.voxel_size);
    grid.setLeafSize(leaf, leaf, leaf);
    grid.setInputCloud(pc);
    PclCloud::Ptr out(new PclCloud);
    grid.filter(*out);
    pc = out;
  }
  if (options.outlier_neighbors > 0 && static_cast<int>(pc->size()) > options.outlier_neighbors) {
    pcl::StatisticalOutlierRemoval<pcl::PointNormal> sor;
    sor.setMeanK(options.outlier_neighbors);
    sor.setStddevMulThresh(options.outlier_stddev);
    sor.setInputCloud(pc);
    PclCloud::Ptr out(new PclCloud);
    sor.filter(*out);
    pc = out;
  }
  if (options.normal_neighbors > 0 && static_cast<int>(pc->size()) > options.normal_neighbors) {
    pcl::NormalEstimation<pcl::PointNormal, pcl::PointNormal> ne;
    pcl::search::KdTree<pcl::PointNormal>::Ptr tree(new pcl::search::KdTree<pcl::PointNormal>);
    ne.setSearchMethod(tree);
    ne.setKSearch(options.normal_neighbors);
    ne.setViewPoint(static_cast<float>(viewpoint.x()), static_cast<float>(viewpoint.y()),
                    static_cast<float>(viewpoint.z()));
    ne.setInputCloud(pc);
    pcl::PointCloud<pcl::PointNormal> with_normals;
    ne.compute(with_normals);
    for (size_t i = 0; i < pc->size(); ++i) {
      (*pc)[i].normal_x = with_normals[i].normal_x;
      (*pc)[i].normal_y = with_normals[i].normal_y;
      (*pc)[i].normal_z = with_normals[i].normal_z;
    }
    normals = true;
  }
  FromPcl(*pc, normals, cloud, labels);
  // Normal estimation leaves NaN normals where a neighbourhood is degenerate.
  DropNonFinite(cloud);
}

}  // namespace femreg
