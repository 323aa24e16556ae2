// Disjoint sets (union-find) over 0..n-1, the one copy: connected pieces of a mesh, cracks
// and pieces in fracture, merged vertices in meshing.
#ifndef FEMREG_MESH_DISJOINT_SETS_H_
#define FEMREG_MESH_DISJOINT_SETS_H_

#include <numeric>
#include <utility>
#include <vector>

namespace femreg {

// Path halving; a union keeps the smaller root, so a set is named by its smallest member
// whatever the order of the unions.
class DisjointSets {
 public:
  explicit DisjointSets(int n) : parent_(static_cast<size_t>(n)) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int size() const { return static_cast<int>(parent_.size()); }
  // The smallest member of i's set.
  int Find(int i) {
    while (parent_[static_cast<size_t>(i)] != i) {
      int& p = parent_[static_cast<size_t>(i)];
      p = parent_[static_cast<size_t>(p)];
      i = p;
    }
    return i;
  }
  void Unite(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return;
    if (a > b) std::swap(a, b);
    parent_[static_cast<size_t>(b)] = a;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace femreg

#endif  // FEMREG_MESH_DISJOINT_SETS_H_
