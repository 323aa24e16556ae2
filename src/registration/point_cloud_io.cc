// Point clouds through PCL: PCD and PLY readers, the binary PCD writer and the filters.
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/crop_box.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "femreg/point_cloud.h"

namespace femreg {

namespace {

using PclCloud = pcl::PointCloud<pcl::PointNormal>;

bool HasField(const pcl::PCLPointCloud2& blob, const std::string& name) {
  for (const auto& f : blob.fields) {
    if (f.name == name) return true;
  }
  return false;
}

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

Status ReadBlob(const std::string& path, bool ply, PointCloud* cloud) {
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int rc = -1;
  try {  // PCL throws when it cannot open or parse the file
    if (ply) {
      pcl::PLYReader reader;
      int version = 0;
      rc = reader.read(path, blob, origin, orientation, version);
    } else {
      pcl::PCDReader reader;
      int version = 0;
      rc = reader.read(path, blob, origin, orientation, version);
    }
  } catch (const std::exception&) {
    rc = -1;
  }
  if (rc < 0) {
    return Status::Error(path + ": could not read as " + (ply ? "PLY" : "PCD") +
                         " (truncated or malformed file)");
  }
  if (!HasField(blob, "x") || !HasField(blob, "y") || !HasField(blob, "z")) {
    return Status::Error(path + ": the cloud has no x, y, z fields");
  }
  const bool normals =
      HasField(blob, "normal_x") && HasField(blob, "normal_y") && HasField(blob, "normal_z");
  PclCloud pcl_cloud;
  pcl::fromPCLPointCloud2(blob, pcl_cloud);
  FromPcl(pcl_cloud, normals, cloud);
  if (HasField(blob, "label")) {
    pcl::PointCloud<pcl::PointXYZL> labelled;
    pcl::fromPCLPointCloud2(blob, labelled);
    cloud->labels.resize(static_cast<Eigen::Index>(labelled.size()));
    for (size_t i = 0; i < labelled.size(); ++i) {
      cloud->labels(static_cast<Eigen::Index>(i)) = static_cast<int>(labelled[i].label);
    }
  }
  return Status::Ok();
}

Status ReadText(const std::string& path, PointCloud* cloud) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open");
  std::vector<double> pts, nrm;
  std::string line;
  int line_no = 0;
  int columns = -1;
  while (std::getline(in, line)) {
    ++line_no;
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    for (char& c : line) {
      if (c == ',' || c == ';') c = ' ';
    }
    std::istringstream ls(line);
    std::vector<double> values;
    std::string token;
    while (ls >> token) {
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') {
        std::ostringstream os;
        os << path << ":" << line_no << ": not a number: '" << token << "'";
        return Status::Error(os.str());
      }
      values.push_back(v);
    }
    if (values.size() != 3 && values.size() != 6) {
      std::ostringstream os;
      os << path << ":" << line_no << ": expected 'x y z' or 'x y z nx ny nz', got "
         << values.size() << " values";
      return Status::Error(os.str());
    }
    if (columns < 0) columns = static_cast<int>(values.size());
    if (static_cast<int>(values.size()) != columns) {
      std::ostringstream os;
      os << path << ":" << line_no << ": " << values.size() << " values where earlier lines had "
         << columns;
      return Status::Error(os.str());
    }
    pts.insert(pts.end(), values.begin(), values.begin() + 3);
    if (columns == 6) nrm.insert(nrm.end(), values.begin() + 3, values.end());
  }
  const Eigen::Index n = static_cast<Eigen::Index>(pts.size() / 3);
  cloud->points = Eigen::Map<Vertices>(pts.data(), n, 3);
  if (columns == 6) {
    cloud->normals = Eigen::Map<Vertices>(nrm.data(), n, 3);
  } else {
    cloud->normals.resize(0, 3);
  }
  return Status::Ok();
}

}  // namespace

int DropNonFinite(PointCloud* cloud) {
  const bool normals = cloud->has_normals();
  const bool labels = cloud->has_labels();
  int kept = 0;
  for (int i = 0; i < cloud->size(); ++i) {
    bool ok = cloud->points.row(i).allFinite();
    if (normals) ok = ok && cloud->normals.row(i).allFinite();
    if (!ok) continue;
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

Status ReadPointCloud(const std::string& path, PointCloud* cloud, int* nonfinite_dropped) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open");
  std::string head(256, '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  in.close();
  Status status;
  if (head.compare(0, 3, "ply") == 0) {
    status = ReadBlob(path, true, cloud);
  } else if (head.find("# .PCD") != std::string::npos ||
             head.compare(0, 7, "VERSION") == 0 || head.find("\nFIELDS") != std::string::npos) {
    status = ReadBlob(path, false, cloud);
  } else {
    status = ReadText(path, cloud);
  }
  if (!status.ok()) return status;
  const int dropped = DropNonFinite(cloud);
  if (nonfinite_dropped) *nonfinite_dropped = dropped;
  return Status::Ok();
}

Status WritePointCloud(const std::string& path, const PointCloud& cloud) {
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
                          int* nonfinite_dropped, const Eigen::Vector3d& viewpoint) {
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
