// Connected pieces of a tetrahedral mesh (union-find over the elements' vertices).
#include <algorithm>
#include <map>
#include <numeric>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {

int ConnectedPieces(const TetMesh& mesh, std::vector<int>* vertex_piece) {
  const int nv = mesh.num_vertices();
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (int k = 1; k < 4; ++k) {
      const int a = find(mesh.tets(t, 0)), b = find(mesh.tets(t, k));
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  vertex_piece->assign(nv, -1);
  std::map<int, int> ids;
  int count = 0;
  for (int v = 0; v < nv; ++v) {
    const int root = find(v);
    auto it = ids.find(root);
    if (it == ids.end()) it = ids.emplace(root, count++).first;
    (*vertex_piece)[v] = it->second;
  }
  return count;
}

}  // namespace femreg
