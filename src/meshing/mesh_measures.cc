// MeshingOptions::IsValid and the measures of a finished mesh (mesh_measures.h).
#include "meshing/mesh_measures.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace femreg {

namespace internal {
std::string Fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}
}  // namespace internal

namespace {

using internal::Fmt;

}  // namespace

bool MeshingOptions::IsValid(std::string* error) const {
  auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (!(std::isfinite(edge_length) && edge_length >= 0.0)) {
    return fail("edge_length must be >= 0 (0: the surface's mean edge length), got " +
                Fmt(edge_length));
  }
  if (!(std::isfinite(max_volume) && max_volume >= 0.0)) {
    return fail("max_volume must be >= 0 (0: from edge_length), got " + Fmt(max_volume));
  }
  if (!(std::isfinite(radius_edge_ratio) && radius_edge_ratio >= 1.1)) {
    return fail("radius_edge_ratio must be >= 1.1 (TetGen may not terminate below), got " +
                Fmt(radius_edge_ratio));
  }
  if (!(std::isfinite(min_dihedral_deg) && min_dihedral_deg >= 0.0 && min_dihedral_deg <= 18.0)) {
    return fail("min_dihedral_deg must be in [0, 18] degrees, got " + Fmt(min_dihedral_deg));
  }
  if (!std::isfinite(merge_distance)) {
    return fail("merge_distance must be finite (negative: automatic), got " + Fmt(merge_distance));
  }
  if (!(feature_angle_deg > 0.0 && feature_angle_deg <= 180.0)) {
    return fail("feature_angle_deg must be in (0, 180] degrees (180: no feature lines), got " +
                Fmt(feature_angle_deg));
  }
  if (remesh_iterations < 1 || remesh_iterations > 100) {
    return fail("remesh_iterations must be in [1, 100], got " + std::to_string(remesh_iterations));
  }
  if (!(std::isfinite(wrap) && wrap >= 0.0)) {
    return fail("wrap must be >= 0 (0: no wrap; else the alpha wrap's alpha), got " + Fmt(wrap));
  }
  if (!(std::isfinite(wrap_offset) && wrap_offset >= 0.0)) {
    return fail("wrap_offset must be >= 0 (0: wrap / 30), got " + Fmt(wrap_offset));
  }
  if (max_tets < 1) return fail("max_tets must be >= 1, got " + std::to_string(max_tets));
  if (!(std::isfinite(time_limit_seconds) && time_limit_seconds >= 0.0)) {
    return fail("time_limit_seconds must be >= 0 (0: no limit), got " + Fmt(time_limit_seconds));
  }
  return true;
}

namespace internal {

void DihedralRange(const TetMesh& mesh, int t, double* min_deg, double* max_deg) {
  Eigen::Vector3d p[4];
  for (int k = 0; k < 4; ++k) p[k] = mesh.rest.row(mesh.tets(t, k)).transpose();
  // The outward normal of the face opposite each corner; the interior angle between faces
  // k and l is pi minus the angle between their outward normals.
  Eigen::Vector3d n[4];
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& a = p[(k + 1) % 4];
    const Eigen::Vector3d& b = p[(k + 2) % 4];
    const Eigen::Vector3d& c = p[(k + 3) % 4];
    n[k] = (b - a).cross(c - a).normalized();
    if (n[k].dot(p[k] - a) > 0.0) n[k] = -n[k];
  }
  *min_deg = 180.0;
  *max_deg = 0.0;
  for (int k = 0; k < 4; ++k) {
    for (int l = k + 1; l < 4; ++l) {
      const double c = std::clamp(-n[k].dot(n[l]), -1.0, 1.0);
      const double deg = std::acos(c) * 180.0 / 3.14159265358979323846;
      *min_deg = std::min(*min_deg, deg);
      *max_deg = std::max(*max_deg, deg);
    }
  }
}

void MeasureMesh(const TetMesh& mesh, MeshingReport* report) {
  const int nt = mesh.num_tets();
  report->vertices = mesh.num_vertices();
  report->tets = mesh.num_tets();
  report->boundary_triangles = mesh.num_surface_triangles();
  report->regions = mesh.num_tets() > 0 ? mesh.region.maxCoeff() + 1 : 0;
  report->mesh_volume = RestVolume(mesh);
  report->quality = ComputeQuality(mesh, mesh.rest);
  std::vector<uint64_t> edges;
  edges.reserve(6 * static_cast<size_t>(nt));
  for (int t = 0; t < nt; ++t) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        uint64_t a = static_cast<uint32_t>(mesh.tets(t, i)),
                 b = static_cast<uint32_t>(mesh.tets(t, j));
        if (a > b) std::swap(a, b);
        edges.push_back(a << 32 | b);
      }
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  double sum = 0.0;
  report->min_edge_length = std::numeric_limits<double>::infinity();
  for (uint64_t e : edges) {
    const double l = (mesh.rest.row(static_cast<int>(e >> 32)) -
                      mesh.rest.row(static_cast<int>(e & 0xffffffffu)))
                         .norm();
    sum += l;
    report->min_edge_length = std::min(report->min_edge_length, l);
    report->max_edge_length = std::max(report->max_edge_length, l);
  }
  report->mean_edge_length = sum / static_cast<double>(edges.size());
  int small = 0, large = 0;
  for (int t = 0; t < nt; ++t) {
    double lo = 0.0, hi = 0.0;
    DihedralRange(mesh, t, &lo, &hi);
    small += lo < 10.0 ? 1 : 0;
    large += hi > 170.0 ? 1 : 0;
  }
  report->small_dihedral_share = nt > 0 ? static_cast<double>(small) / nt : 0.0;
  report->large_dihedral_share = nt > 0 ? static_cast<double>(large) / nt : 0.0;
}

}  // namespace internal
}  // namespace femreg
