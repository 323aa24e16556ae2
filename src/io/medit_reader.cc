// MEDIT .mesh (ASCII): Vertices and Tetrahedra (reference -> region); other blocks skipped.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>

#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {

Status ReadMeditFile(const std::string& path, RawTetMesh* raw) {
  TokenStream in;
  Status s = in.Open(path, '#');
  if (!s.ok()) return s;
  // Numbers per entry of the blocks we skip.
  const std::map<std::string, int> kSkipped = {
      {"Edges", 3},          {"Triangles", 4},        {"Quadrilaterals", 5},
      {"Hexahedra", 9},      {"Prisms", 7},           {"Pyramids", 6},
      {"Corners", 1},        {"Ridges", 1},           {"RequiredVertices", 1},
      {"RequiredEdges", 1},  {"RequiredTriangles", 1}, {"Normals", 3},
      {"Tangents", 3},       {"NormalAtVertices", 2}, {"TangentAtVertices", 2},
      {"NormalAtTriangleVertices", 3}, {"TangentAtEdges", 3}, {"Identifier", 0},
      {"Geometry", 0}};
  int dimension = 3;
  bool saw_vertices = false, saw_tets = false, saw_end = false;
  Token t;
  while (!saw_end && in.Next(&t)) {
    const std::string keyword = t.text;
    long long n = 0;
    if (keyword == "End") {
      saw_end = true;
    } else if (keyword == "MeshVersionFormatted") {
      if (!(s = in.NextInt("the version", &n)).ok()) return s;
    } else if (keyword == "Dimension") {
      if (!(s = in.NextInt("the dimension", &n)).ok()) return s;
      if (n != 3) return in.Error("only 3-dimensional meshes are supported");
      dimension = static_cast<int>(n);
    } else if (keyword == "Vertices") {
      if (!(s = in.NextInt("the number of vertices", &n)).ok()) return s;
      saw_vertices = true;
      for (long long i = 0; i < n; ++i) {
        std::array<double, 3> xyz;
        for (int k = 0; k < dimension; ++k) {
          if (!(s = in.NextDouble("a vertex coordinate", &xyz[k])).ok()) return s;
          if (!std::isfinite(xyz[k])) {
            std::ostringstream os;
            os << "vertex " << i + 1 << " has a non-finite coordinate";
            return in.Error(os.str());
          }
        }
        long long ref;
        if (!(s = in.NextInt("a vertex reference", &ref)).ok()) return s;
        raw->vertices.push_back(xyz);
      }
    } else if (keyword == "Tetrahedra") {
      if (!(s = in.NextInt("the number of tetrahedra", &n)).ok()) return s;
      saw_tets = true;
      for (long long i = 0; i < n; ++i) {
        std::array<int, 4> tet;
        int line = 0;
        for (int k = 0; k < 4; ++k) {
          long long v;
          if (!(s = in.NextInt("a vertex index", &v)).ok()) return s;
          if (k == 0) line = in.line();
          if (v < 1 || v > static_cast<long long>(raw->vertices.size())) {
            std::ostringstream os;
            os << "tetrahedron " << i + 1 << " refers to vertex " << v << ", outside 1.."
               << raw->vertices.size() << " (index out of range)";
            return in.Error(os.str());
          }
          tet[k] = static_cast<int>(v - 1);
        }
        long long ref;
        if (!(s = in.NextInt("a tetrahedron reference", &ref)).ok()) return s;
        raw->tets.push_back(tet);
        raw->regions.push_back(static_cast<int>(ref));
        raw->tet_lines.push_back(line);
      }
    } else {
      auto it = kSkipped.find(keyword);
      if (it == kSkipped.end()) return in.Error("unknown MEDIT keyword " + Quoted(keyword));
      if (it->second == 0) continue;
      if (!(s = in.NextInt("the number of entries", &n)).ok()) return s;
      if (!(s = in.CheckCount(("the number of " + keyword).c_str(), n, it->second)).ok()) return s;
      for (long long i = 0; i < n * it->second; ++i) {
        double v;
        if (!(s = in.NextDouble(("an entry of " + keyword).c_str(), &v)).ok()) return s;
      }
    }
  }
  if (!saw_vertices) return in.Error("no Vertices block (truncated file?)");
  if (!saw_tets) return in.Error("no tetrahedra (no Tetrahedra block)");
  return Status::Ok();
}

}  // namespace internal
}  // namespace femreg
