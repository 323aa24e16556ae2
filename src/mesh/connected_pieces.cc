// Connected pieces of a tetrahedral mesh (union-find over the elements' vertices).
#include <map>
#include <vector>

#include "femreg/mesh.h"
#include "mesh/disjoint_sets.h"

namespace femreg {

int ConnectedPieces(const TetMesh& mesh, std::vector<int>* vertex_piece) {
  const int nv = mesh.num_vertices();
  DisjointSets sets(nv);
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (int k = 1; k < 4; ++k) sets.Unite(mesh.tets(t, 0), mesh.tets(t, k));
  }
  vertex_piece->assign(nv, -1);
  std::map<int, int> ids;
  int count = 0;
  for (int v = 0; v < nv; ++v) {
    const int root = sets.Find(v);
    auto it = ids.find(root);
    if (it == ids.end()) it = ids.emplace(root, count++).first;
    (*vertex_piece)[v] = it->second;
  }
  return count;
}

}  // namespace femreg
