// Triangle surfaces (rigid obstacles, surfaces to mesh): OBJ (v / f, polygons fanned, negative indices,
// v/vt/vn forms) and STL (ASCII or binary, vertices merged by exact position).
#include <array>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/io.h"

namespace femreg {

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

Status ReadObj(const std::string& path, std::istream& in, Vertices* vertices, Triangles* triangles) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> f;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag)) continue;
    if (tag == "v") {
      Eigen::Vector3d p;
      if (!(ls >> p.x() >> p.y() >> p.z()) || !p.allFinite()) {
        return Status::Error(path + ":" + std::to_string(line_number) + ": bad vertex");
      }
      v.push_back(p);
    } else if (tag == "f") {
      std::vector<int> poly;
      std::string token;
      while (ls >> token) {
        const int i = std::atoi(token.substr(0, token.find('/')).c_str());
        const int index = i > 0 ? i - 1 : static_cast<int>(v.size()) + i;
        if (i == 0 || index < 0 || index >= static_cast<int>(v.size())) {
          return Status::Error(path + ":" + std::to_string(line_number) + ": bad face index '" +
                               token + "'");
        }
        poly.push_back(index);
      }
      if (poly.size() < 3) {
        return Status::Error(path + ":" + std::to_string(line_number) + ": a face needs 3 vertices");
      }
      for (size_t k = 1; k + 1 < poly.size(); ++k) f.emplace_back(poly[0], poly[k], poly[k + 1]);
    }
  }
  vertices->resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) vertices->row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  triangles->resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) triangles->row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  return Status::Ok();
}

// Merges STL corners by exact coordinates.
struct Welder {
  std::map<std::array<double, 3>, int> index;
  std::vector<Eigen::Vector3d> v;
  int Add(const Eigen::Vector3d& p) {
    auto it = index.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, static_cast<int>(v.size()));
    if (it.second) v.push_back(p);
    return it.first->second;
  }
};

Status ReadStl(const std::string& path, const std::string& bytes, Vertices* vertices,
               Triangles* triangles) {
  Welder w;
  std::vector<Eigen::Vector3i> f;
  bool binary = true;
  if (bytes.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    binary = bytes.size() == 84 + 50 * static_cast<size_t>(count);
  } else {
    binary = false;
  }
  if (binary) {
    uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    for (uint32_t t = 0; t < count; ++t) {
      const char* rec = bytes.data() + 84 + 50 * static_cast<size_t>(t);
      Eigen::Vector3i tri;
      for (int k = 0; k < 3; ++k) {
        float c[3];
        std::memcpy(c, rec + 12 + 12 * k, 12);
        const Eigen::Vector3d p(c[0], c[1], c[2]);
        if (!p.allFinite()) return Status::Error(path + ": triangle " + std::to_string(t) + " is not finite");
        tri[k] = w.Add(p);
      }
      f.push_back(tri);
    }
  } else {
    std::istringstream in(bytes);
    std::string token;
    std::vector<int> corners;
    if (!(in >> token) || Lower(token) != "solid") {
      return Status::Error(path + ": neither binary STL (size does not match its triangle count) nor ASCII STL (no 'solid')");
    }
    while (in >> token) {
      if (Lower(token) == "vertex") {
        Eigen::Vector3d p;
        if (!(in >> p.x() >> p.y() >> p.z()) || !p.allFinite()) {
          return Status::Error(path + ": bad vertex after facet " + std::to_string(f.size()));
        }
        corners.push_back(w.Add(p));
      } else if (Lower(token) == "endfacet") {
        if (corners.size() != 3) {
          return Status::Error(path + ": facet " + std::to_string(f.size()) + " has " +
                               std::to_string(corners.size()) + " vertices, not 3");
        }
        f.emplace_back(corners[0], corners[1], corners[2]);
        corners.clear();
      }
    }
  }
  vertices->resize(static_cast<Eigen::Index>(w.v.size()), 3);
  for (size_t i = 0; i < w.v.size(); ++i) vertices->row(static_cast<Eigen::Index>(i)) = w.v[i].transpose();
  triangles->resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) triangles->row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  return Status::Ok();
}

}  // namespace

Status ReadTriangleSurface(const std::string& path, Vertices* vertices, Triangles* triangles) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string ext = Lower(path.size() >= 4 ? path.substr(path.size() - 4) : path);
  Status status;
  if (ext == ".obj") {
    std::istringstream s(bytes);
    status = ReadObj(path, s, vertices, triangles);
  } else if (ext == ".stl") {
    status = ReadStl(path, bytes, vertices, triangles);
  } else {
    return Status::Error(path + ": unknown surface format (expected .obj or .stl)");
  }
  if (!status.ok()) return status;
  if (triangles->rows() == 0) return Status::Error(path + ": no triangle");
  return Status::Ok();
}

}  // namespace femreg
