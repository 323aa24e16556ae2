// Mesh checks (CheckMesh: volumes, orphan vertices, surface edges and vertices, pieces), run
// on meshes that fracture has split; see femreg/fracture.h.
#include <algorithm>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fracture.h"

namespace femreg {

MeshValidity CheckMesh(const TetMesh& mesh) {
  MeshValidity v;
  const int nv = mesh.num_vertices();
  std::vector<int> count(nv, 0);
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const double vol = SignedTetVolume(mesh.rest.row(mesh.tets(t, 0)), mesh.rest.row(mesh.tets(t, 1)),
                                       mesh.rest.row(mesh.tets(t, 2)), mesh.rest.row(mesh.tets(t, 3)));
    if (!(vol > 0)) ++v.nonpositive_volumes;
    for (int k = 0; k < 4; ++k) ++count[mesh.tets(t, k)];
  }
  for (int c : count) v.orphan_vertices += (c == 0);
  // Directed surface edges: a closed oriented manifold has each undirected edge exactly
  // once in each direction.
  std::map<std::pair<int, int>, std::pair<int, int>> edges;  // (min, max) -> (forward, backward)
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.surface(f, k), b = mesh.surface(f, (k + 1) % 3);
      auto& e = edges[{std::min(a, b), std::max(a, b)}];
      (a < b ? e.first : e.second)++;
    }
  }
  for (const auto& kv : edges) {
    const int total = kv.second.first + kv.second.second;
    if (total > 2) {
      ++v.nonmanifold_edges;
    } else if (total != 2 || kv.second.first != 1) {
      ++v.open_edges;
    }
  }
  // Vertex fans: the triangles around a surface vertex, linked through their edges at the
  // vertex, must form one cycle.
  std::vector<std::vector<int>> vertex_faces(nv);
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) vertex_faces[mesh.surface(f, k)].push_back(f);
  }
  for (int u = 0; u < nv; ++u) {
    const auto& faces = vertex_faces[u];
    if (faces.empty()) continue;
    // Map "next vertex" -> face: following the fan through the outgoing edge u->b.
    std::map<int, int> out_edge;  // b -> face where u->b is a directed edge
    std::map<int, int> in_edge;   // a -> face where a->u is a directed edge
    for (int f : faces) {
      for (int k = 0; k < 3; ++k) {
        if (mesh.surface(f, k) != u) continue;
        out_edge[mesh.surface(f, (k + 1) % 3)] = f;
        in_edge[mesh.surface(f, (k + 2) % 3)] = f;
      }
    }
    // Walk: from face f with u->b, the next face has b->u.
    std::vector<char> seen(faces.size(), 0);
    std::map<int, size_t> index;
    for (size_t i = 0; i < faces.size(); ++i) index[faces[i]] = i;
    int f = faces[0];
    size_t steps = 0;
    while (!seen[index[f]] && steps <= faces.size()) {
      seen[index[f]] = 1;
      ++steps;
      int b = -1;
      for (int k = 0; k < 3; ++k) {
        if (mesh.surface(f, k) == u) b = mesh.surface(f, (k + 1) % 3);
      }
      auto it = in_edge.find(b);
      if (it == in_edge.end()) break;
      f = it->second;
    }
    if (steps != faces.size()) ++v.nonmanifold_vertices;
  }
  std::vector<int> piece;
  v.pieces = ConnectedPieces(mesh, &piece);
  return v;
}

std::string MeshValidity::ToString() const {
  std::ostringstream os;
  os << nonpositive_volumes << " non-positive volumes, " << orphan_vertices << " orphan vertices, "
     << open_edges << " open edges, " << nonmanifold_edges << " non-manifold edges, "
     << nonmanifold_vertices << " non-manifold vertices, " << pieces << " piece(s)";
  return os.str();
}

}  // namespace femreg
