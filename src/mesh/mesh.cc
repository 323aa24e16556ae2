#include "femreg/mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <unordered_map>

namespace femreg {

double SignedTetVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

namespace {

// The four faces of tet (0,1,2,3), each ordered so that its right-hand normal points away
// from the opposite vertex when the tet is positively oriented.
constexpr int kTetFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

struct FaceKey {
  std::array<int, 3> v;
  bool operator==(const FaceKey& o) const { return v == o.v; }
};
struct FaceKeyHash {
  size_t operator()(const FaceKey& k) const {
    size_t h = static_cast<size_t>(k.v[0]) * 73856093u;
    h ^= static_cast<size_t>(k.v[1]) * 19349663u + (h << 6) + (h >> 2);
    h ^= static_cast<size_t>(k.v[2]) * 83492791u + (h << 6) + (h >> 2);
    return h;
  }
};

double MeanEdgeLength(const TetMesh& mesh) {
  double sum = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        sum += (mesh.rest.row(mesh.tets(t, i)) - mesh.rest.row(mesh.tets(t, j))).norm();
      }
    }
  }
  return mesh.num_tets() > 0 ? sum / (6.0 * mesh.num_tets()) : 0.0;
}

}  // namespace

void BuildTopology(TetMesh* mesh) {
  const int nv = mesh->num_vertices();
  const int nt = mesh->num_tets();

  // Faces seen once are boundary faces.
  std::unordered_map<FaceKey, std::pair<int, std::array<int, 3>>, FaceKeyHash> faces;
  faces.reserve(static_cast<size_t>(nt) * 4);
  for (int t = 0; t < nt; ++t) {
    for (const auto& f : kTetFaces) {
      std::array<int, 3> oriented = {mesh->tets(t, f[0]), mesh->tets(t, f[1]), mesh->tets(t, f[2])};
      FaceKey key{oriented};
      std::sort(key.v.begin(), key.v.end());
      auto it = faces.find(key);
      if (it == faces.end()) {
        faces.emplace(key, std::make_pair(1, oriented));
      } else {
        ++it->second.first;
      }
    }
  }
  std::vector<std::array<int, 3>> boundary;
  for (const auto& kv : faces) {
    if (kv.second.first == 1) boundary.push_back(kv.second.second);
  }
  // Deterministic order whatever the hash table did.
  std::sort(boundary.begin(), boundary.end());
  mesh->surface.resize(static_cast<Eigen::Index>(boundary.size()), 3);
  std::vector<char> on_surface(nv, 0);
  for (size_t i = 0; i < boundary.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      mesh->surface(static_cast<Eigen::Index>(i), k) = boundary[i][k];
      on_surface[boundary[i][k]] = 1;
    }
  }
  mesh->surface_vertices.clear();
  for (int v = 0; v < nv; ++v) {
    if (on_surface[v]) mesh->surface_vertices.push_back(v);
  }

  mesh->vertex_tet_offsets.assign(nv + 1, 0);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) ++mesh->vertex_tet_offsets[mesh->tets(t, k) + 1];
  }
  for (int v = 0; v < nv; ++v) mesh->vertex_tet_offsets[v + 1] += mesh->vertex_tet_offsets[v];
  mesh->vertex_tets.assign(mesh->vertex_tet_offsets[nv], 0);
  std::vector<int> fill(mesh->vertex_tet_offsets.begin(), mesh->vertex_tet_offsets.end() - 1);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) mesh->vertex_tets[fill[mesh->tets(t, k)]++] = t;
  }
}

Status FinalizeMesh(TetMesh* mesh, const std::string& source, double degenerate_tolerance) {
  const int nv = mesh->num_vertices();
  const int nt = mesh->num_tets();
  if (nv == 0) return Status::Error(source + ": no vertices");
  if (nt == 0) return Status::Error(source + ": no tetrahedra");
  for (int v = 0; v < nv; ++v) {
    if (!mesh->rest.row(v).allFinite()) {
      std::ostringstream os;
      os << source << ": vertex " << v << " has a non-finite coordinate";
      return Status::Error(os.str());
    }
  }
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) {
      const int v = mesh->tets(t, k);
      if (v < 0 || v >= nv) {
        std::ostringstream os;
        os << source << ": element " << t << " refers to vertex " << v << ", outside 0.."
           << nv - 1;
        return Status::Error(os.str());
      }
    }
  }
  if (mesh->region.size() != nt) mesh->region = Eigen::VectorXi::Zero(nt);

  const double h = MeanEdgeLength(*mesh);
  const double min_volume = degenerate_tolerance * h * h * h;
  for (int t = 0; t < nt; ++t) {
    const double vol =
        SignedTetVolume(mesh->rest.row(mesh->tets(t, 0)), mesh->rest.row(mesh->tets(t, 1)),
                        mesh->rest.row(mesh->tets(t, 2)), mesh->rest.row(mesh->tets(t, 3)));
    if (std::abs(vol) <= min_volume) {
      std::ostringstream os;
      os << source << ": element " << t << " (vertices " << mesh->tets(t, 0) << " "
         << mesh->tets(t, 1) << " " << mesh->tets(t, 2) << " " << mesh->tets(t, 3)
         << ") is degenerate: volume " << vol;
      return Status::Error(os.str());
    }
    if (vol < 0) std::swap(mesh->tets(t, 2), mesh->tets(t, 3));
  }
  mesh->x = mesh->rest;
  BuildTopology(mesh);
  if (mesh->mass.size() != nv) mesh->mass = Eigen::VectorXd::Zero(nv);
  return Status::Ok();
}

void ComputeLumpedMasses(TetMesh* mesh, double default_density,
                         const std::vector<std::pair<int, double>>& density_per_region) {
  mesh->mass = Eigen::VectorXd::Zero(mesh->num_vertices());
  for (int t = 0; t < mesh->num_tets(); ++t) {
    double density = default_density;
    for (const auto& rd : density_per_region) {
      if (rd.first == mesh->region(t)) density = rd.second;
    }
    const double vol = std::abs(
        SignedTetVolume(mesh->rest.row(mesh->tets(t, 0)), mesh->rest.row(mesh->tets(t, 1)),
                        mesh->rest.row(mesh->tets(t, 2)), mesh->rest.row(mesh->tets(t, 3))));
    for (int k = 0; k < 4; ++k) mesh->mass(mesh->tets(t, k)) += 0.25 * density * vol;
  }
}

double RestVolume(const TetMesh& mesh) {
  double total = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    total += SignedTetVolume(mesh.rest.row(mesh.tets(t, 0)), mesh.rest.row(mesh.tets(t, 1)),
                             mesh.rest.row(mesh.tets(t, 2)), mesh.rest.row(mesh.tets(t, 3)));
  }
  return total;
}

MeshQuality ComputeQuality(const TetMesh& mesh, const Vertices& positions) {
  MeshQuality q;
  q.min_dihedral_deg = 180.0;
  q.max_dihedral_deg = 0.0;
  double aspect_sum = 0.0;
  int aspect_count = 0;
  double h_sum = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        h_sum += (positions.row(mesh.tets(t, i)) - positions.row(mesh.tets(t, j))).norm();
  }
  const double h = mesh.num_tets() > 0 ? h_sum / (6.0 * mesh.num_tets()) : 0.0;
  const double min_volume = 1e-12 * h * h * h;
  const double kPi = 3.14159265358979323846;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    Eigen::Vector3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = positions.row(mesh.tets(t, k)).transpose();
    const double vol = SignedTetVolume(p[0], p[1], p[2], p[3]);
    if (std::abs(vol) <= min_volume) {
      ++q.num_degenerate;
      if (q.degenerate.size() < 100) q.degenerate.push_back(t);
      continue;
    }
    if (vol < 0) {
      ++q.num_inverted;
      if (q.inverted.size() < 100) q.inverted.push_back(t);
    }
    // Face normals (outward for a positive tet) and areas.
    Eigen::Vector3d n[4];
    double area_sum = 0.0;
    for (int f = 0; f < 4; ++f) {
      const Eigen::Vector3d a = p[kTetFaces[f][0]], b = p[kTetFaces[f][1]], c = p[kTetFaces[f][2]];
      Eigen::Vector3d nn = (b - a).cross(c - a);
      area_sum += 0.5 * nn.norm();
      n[f] = nn.normalized();
    }
    // Dihedral angle between faces f and g: pi - angle between outward normals.
    for (int f = 0; f < 4; ++f) {
      for (int g = f + 1; g < 4; ++g) {
        const double c = std::max(-1.0, std::min(1.0, n[f].dot(n[g])));
        const double angle = (kPi - std::acos(c)) * 180.0 / kPi;
        q.min_dihedral_deg = std::min(q.min_dihedral_deg, angle);
        q.max_dihedral_deg = std::max(q.max_dihedral_deg, angle);
      }
    }
    double longest = 0.0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) longest = std::max(longest, (p[i] - p[j]).norm());
    const double inradius = 3.0 * std::abs(vol) / area_sum;
    const double aspect = longest / (2.0 * std::sqrt(6.0) * inradius);
    q.max_aspect_ratio = std::max(q.max_aspect_ratio, aspect);
    aspect_sum += aspect;
    ++aspect_count;
  }
  q.mean_aspect_ratio = aspect_count > 0 ? aspect_sum / aspect_count : 0.0;
  if (mesh.num_tets() == 0) q.min_dihedral_deg = 0.0;
  return q;
}

}  // namespace femreg
