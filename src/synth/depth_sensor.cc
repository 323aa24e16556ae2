#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "femreg/point_cloud.h"  // CameraRotation
#include "femreg/synth.h"
#include "geometry/zbuffer.h"
#include "synth/sensor_artefacts.h"

namespace femreg {

namespace {

PinholeCamera Pinhole(const DepthSensorOptions& options, const Eigen::Matrix3d& R) {
  PinholeCamera p;
  p.rotation = R;
  p.position = options.camera.position;
  p.fx = options.camera.fx;
  p.fy = options.camera.fy;
  p.cx = options.camera.cx;
  p.cy = options.camera.cy;
  p.width = options.camera.width;
  p.height = options.camera.height;
  p.near = options.near;
  return p;
}

}  // namespace

bool SensorArtefacts::IsValid(std::string* error) const {
  std::ostringstream os;
  const auto fraction = [](double v) { return v >= 0 && v <= 1; };
  if (!fraction(flying_fraction) || !(flying_jump > 0)) {
    os << "sensor.flying_pixels needs a fraction in [0, 1] and a jump > 0 (got "
       << flying_fraction << ", " << flying_jump << ")";
  } else if (!(disparity_step >= 0) || !(baseline > 0)) {
    os << "sensor.quantisation needs a step >= 0 and a baseline > 0 (got " << disparity_step
       << ", " << baseline << ")";
  } else if (!fraction(dark_fraction) || !(dark_radius > 0)) {
    os << "sensor.dark_holes needs a fraction in [0, 1] and a radius > 0 (got " << dark_fraction
       << ", " << dark_radius << ")";
  } else if (!(specular_angle_deg >= 0 && specular_angle_deg <= 90)) {
    os << "sensor.specular_holes angle must be in [0, 90] (got " << specular_angle_deg << ")";
  } else if (!(grazing_holes_deg >= 0 && grazing_holes_deg <= 90) || !(hole_blob_px >= 1)) {
    os << "sensor.grazing_holes needs an angle in [0, 90] and blobs >= 1 px (got "
       << grazing_holes_deg << ", " << hole_blob_px << ")";
  } else if (!(multipath_bias >= 0) || !(multipath_radius > 0)) {
    os << "sensor.multipath needs a bias >= 0 and a radius > 0 (got " << multipath_bias << ", "
       << multipath_radius << ")";
  } else if (!(flicker_offset >= 0) || !fraction(flicker_dropout)) {
    os << "sensor.flicker needs an offset >= 0 and a dropout in [0, 1] (got " << flicker_offset
       << ", " << flicker_dropout << ")";
  } else {
    return true;
  }
  if (error) *error = os.str();
  return false;
}

bool DepthSensorOptions::IsValid(std::string* error) const {
  if (!camera.IsValid(error)) return false;
  // "sensor.near must be > 0 (got 0)": the table's ranges (femreg/synth.h), then the artefacts.
  return CheckFieldRanges(*this, error) && artefacts.IsValid(error);
}

DepthSensor::DepthSensor(const DepthSensorOptions& options) : options_(options) {
  R_ = CameraRotation(options.camera);  // the same frame the depth images are read in
}

bool DepthSensor::Project(const Eigen::Vector3d& p, double* u, double* v, double* z) const {
  return Pinhole(options_, R_).Project(p, u, v, z);
}

DepthImage DepthSensor::Render(const std::vector<RenderSurface>& surfaces) const {
  const CameraOptions& c = options_.camera;
  const PinholeCamera pinhole = Pinhole(options_, R_);
  ZBuffer zbuffer;
  zbuffer.Reset(c.width, c.height);
  for (size_t s = 0; s < surfaces.size(); ++s) {
    Rasterize(pinhole, *surfaces[s].positions, *surfaces[s].triangles, static_cast<int>(s), &zbuffer);
  }
  DepthImage img;
  img.width = c.width;
  img.height = c.height;
  img.depth.resize(zbuffer.depth.size());
  for (size_t i = 0; i < zbuffer.depth.size(); ++i) {
    img.depth[i] = zbuffer.triangle[i] >= 0 ? static_cast<float>(zbuffer.depth[i]) : 0.0f;
  }
  img.surface = std::move(zbuffer.surface);
  img.triangle = std::move(zbuffer.triangle);
  return img;
}

PointCloud DepthSensor::Sample(const DepthImage& image, const std::vector<RenderSurface>& surfaces,
                               uint64_t seed) const {
  namespace si = synth_internal;
  const CameraOptions& c = options_.camera;
  const SensorArtefacts& a = options_.artefacts;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // The artefacts' own generator: the clean noise stream is the same with them on or off.
  std::mt19937_64 artefact_rng(seed ^ 0x5eed5a17a11a5ull);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  // A distribution of its own too: a normal distribution keeps the second value of a pair.
  std::normal_distribution<double> artefact_gauss(0.0, 1.0);
  const double flicker =
      a.flicker_offset > 0 ? a.flicker_offset * artefact_gauss(artefact_rng) : 0.0;
  const double cos_grazing = std::cos(options_.grazing_angle_deg * M_PI / 180.0);
  const double cos_specular = std::cos(a.specular_angle_deg * M_PI / 180.0);
  si::ImageGeometry geometry;
  if (a.multipath_bias > 0) geometry = si::ComputeImageGeometry(image, surfaces, c, R_);
  std::vector<std::vector<Eigen::Vector3d>> dark(surfaces.size());
  for (size_t s = 0; s < surfaces.size() && a.dark_fraction > 0; ++s) {
    dark[s] = si::DarkCentres(*surfaces[s].positions, *surfaces[s].triangles, a.dark_fraction,
                              a.dark_radius, 0xda2c0000ull + s);
  }
  std::vector<Eigen::Vector3d> pts;
  for (int py = 0; py < image.height; py += options_.pixel_stride) {
    for (int px = 0; px < image.width; px += options_.pixel_stride) {
      const size_t idx = static_cast<size_t>(py) * image.width + px;
      if (image.triangle[idx] < 0) continue;
      const size_t s = static_cast<size_t>(image.surface[idx]);
      if (!surfaces[s].returns) continue;
      double z = image.depth[idx];
      const Eigen::Vector3d ray_c((px - c.cx) / c.fx, (py - c.cy) / c.fy, 1.0);
      const Eigen::Vector3d dir_w = (R_.transpose() * ray_c).normalized();
      const Vertices& P = *surfaces[s].positions;
      const Triangles& T = *surfaces[s].triangles;
      const int f = image.triangle[idx];
      const Eigen::Vector3d va = P.row(T(f, 0)), vb = P.row(T(f, 1)), vc = P.row(T(f, 2));
      const Eigen::Vector3d n = (vb - va).cross(vc - va).normalized();
      const double cos_incidence = std::abs(n.dot(dir_w));
      if (cos_incidence < cos_grazing) continue;
      const double noise = options_.noise_coefficient * z * z * gauss(rng);
      // Holes: specular, grazing blobs, dark discs, then this frame's random drop-outs.
      if (a.specular_angle_deg > 0 && cos_incidence > cos_specular) continue;
      if (a.grazing_holes_deg > 0) {
        const double angle = std::acos(std::min(1.0, cos_incidence)) * 180.0 / M_PI;
        const double span = options_.grazing_angle_deg - a.grazing_holes_deg;
        const double ramp = span > 0 ? (angle - a.grazing_holes_deg) / span : 1.0;
        if (angle > a.grazing_holes_deg && si::SmoothNoise(px, py, a.hole_blob_px) < ramp) continue;
      }
      if (!dark[s].empty()) {
        const Eigen::Vector3d x = c.position + R_.transpose() * (z * ray_c);
        bool in_dark = false;
        for (const Eigen::Vector3d& centre : dark[s]) {
          in_dark = in_dark || (x - centre).squaredNorm() < a.dark_radius * a.dark_radius;
        }
        if (in_dark) continue;
      }
      if (a.flicker_dropout > 0 && uni(artefact_rng) < a.flicker_dropout) continue;
      if (a.multipath_bias > 0) {
        z += a.multipath_bias * si::ConcaveFraction(image, geometry, c, px, py, a.multipath_radius);
      }
      if (a.flying_fraction > 0) {
        const double other = si::EdgeNeighbourDepth(image, px, py, a.flying_jump);
        // Two draws per pixel, edge or not: which pixels fly does not shift later draws.
        const double u = uni(artefact_rng), t = uni(artefact_rng);
        if (other > 0 && u < a.flying_fraction) z += t * (other - z);
      }
      double depth = z + noise + flicker;
      if (a.disparity_step > 0) {
        depth = si::QuantiseDepth(depth, c.fx, a.baseline, a.disparity_step);
      }
      pts.push_back(c.position + R_.transpose() * (depth * ray_c));
    }
  }
  const size_t num_outliers = static_cast<size_t>(options_.outlier_fraction * pts.size());
  if (num_outliers > 0 && !pts.empty()) {
    Eigen::Vector3d lo = pts[0], hi = pts[0];
    for (const auto& p : pts) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    lo.array() -= options_.outlier_margin;
    hi.array() += options_.outlier_margin;
    for (size_t i = 0; i < num_outliers; ++i) {
      pts.push_back(lo + (hi - lo).cwiseProduct(Eigen::Vector3d(uni(rng), uni(rng), uni(rng))));
    }
  }
  PointCloud cloud;
  cloud.points.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) cloud.points.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  cloud.normals.resize(0, 3);
  return cloud;
}

std::vector<char> DepthSensor::Visible(const DepthImage& image, const Vertices& points,
                                       double tolerance) const {
  std::vector<char> out(static_cast<size_t>(points.rows()), 0);
  for (int i = 0; i < points.rows(); ++i) {
    double u, v, z;
    if (!Project(points.row(i), &u, &v, &z)) continue;
    const int px = static_cast<int>(std::lround(u)), py = static_cast<int>(std::lround(v));
    if (px < 0 || py < 0 || px >= image.width || py >= image.height) continue;
    // The depth at the vertex's own pixel; on a silhouette, where that pixel sees nothing,
    // the nearest depth around it. The pixel centre is up to 0.7 pixels away from the
    // vertex, so an inclined surface differs in depth by a few pixel footprints there.
    double depth = image.depth[static_cast<size_t>(py) * image.width + px];
    if (!(depth > 0)) {
      depth = std::numeric_limits<double>::infinity();
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int qx = px + dx, qy = py + dy;
          if (qx < 0 || qy < 0 || qx >= image.width || qy >= image.height) continue;
          const float d = image.depth[static_cast<size_t>(qy) * image.width + qx];
          if (d > 0) depth = std::min(depth, static_cast<double>(d));
        }
      }
    }
    const double footprint = z / std::min(options_.camera.fx, options_.camera.fy);
    if (std::isfinite(depth) && z <= depth + tolerance + 2.0 * footprint) {
      out[static_cast<size_t>(i)] = 1;
    }
  }
  return out;
}

}  // namespace femreg
