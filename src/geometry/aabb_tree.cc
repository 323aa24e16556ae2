// AABB hierarchy over surface triangles: top-down median build, bottom-up refit, and
// simultaneous descent of two trees (the narrow phase's coarse-to-fine part).
#include <algorithm>

#include "femreg/geometry.h"

namespace femreg {

namespace {

Eigen::AlignedBox3d TriangleBox(const Vertices& x, const Triangles& t, int f) {
  Eigen::AlignedBox3d box(Eigen::Vector3d(x.row(t(f, 0))));
  box.extend(Eigen::Vector3d(x.row(t(f, 1))));
  box.extend(Eigen::Vector3d(x.row(t(f, 2))));
  return box;
}

// Whether two boxes come within `margin` of each other (per axis).
bool Near(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b, double margin) {
  return (a.min().array() <= b.max().array() + margin).all() &&
         (b.min().array() <= a.max().array() + margin).all();
}

}  // namespace

void AabbTree::Build(const Vertices& x, const Triangles& triangles) {
  triangles_ = triangles;
  nodes_.clear();
  const int nf = static_cast<int>(triangles.rows());
  if (nf == 0) return;
  nodes_.reserve(2 * static_cast<size_t>(nf));
  std::vector<int> order(nf);
  for (int f = 0; f < nf; ++f) order[f] = f;
  BuildRange(x, &order, 0, nf);
}

int AabbTree::BuildRange(const Vertices& x, std::vector<int>* order, int begin, int end) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  if (end - begin == 1) {
    nodes_[index].triangle = (*order)[begin];
    nodes_[index].box = TriangleBox(x, triangles_, (*order)[begin]);
    return index;
  }
  Eigen::AlignedBox3d centroids;
  auto centroid = [&](int f) {
    return Eigen::Vector3d((x.row(triangles_(f, 0)) + x.row(triangles_(f, 1)) + x.row(triangles_(f, 2))) / 3.0);
  };
  for (int i = begin; i < end; ++i) centroids.extend(centroid((*order)[i]));
  int axis = 0;
  centroids.sizes().maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(order->begin() + begin, order->begin() + mid, order->begin() + end,
                   [&](int a, int b) { return centroid(a)[axis] < centroid(b)[axis]; });
  const int left = BuildRange(x, order, begin, mid);
  const int right = BuildRange(x, order, mid, end);
  nodes_[index].left = left;
  nodes_[index].right = right;
  nodes_[index].box = nodes_[left].box.merged(nodes_[right].box);
  return index;
}

void AabbTree::Refit(const Vertices& x) {
  for (int i = num_nodes() - 1; i >= 0; --i) {
    Node& n = nodes_[i];
    n.box = n.triangle >= 0 ? TriangleBox(x, triangles_, n.triangle)
                            : nodes_[n.left].box.merged(nodes_[n.right].box);
  }
}

void AabbTree::Overlapping(const AabbTree& other, double margin,
                           std::vector<std::pair<int, int>>* pairs) const {
  pairs->clear();
  if (empty() || other.empty()) return;
  std::vector<std::pair<int, int>> stack = {{0, 0}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    const Node& a = nodes_[i];
    const Node& b = other.nodes_[j];
    if (!Near(a.box, b.box, margin)) continue;
    const bool leaf_a = a.triangle >= 0, leaf_b = b.triangle >= 0;
    if (leaf_a && leaf_b) {
      pairs->emplace_back(a.triangle, b.triangle);
    } else if (leaf_b || (!leaf_a && a.box.volume() >= b.box.volume())) {
      stack.emplace_back(a.left, j);
      stack.emplace_back(a.right, j);
    } else {
      stack.emplace_back(i, b.left);
      stack.emplace_back(i, b.right);
    }
  }
}

void AabbTree::Overlapping(const Eigen::AlignedBox3d& box, double margin,
                           std::vector<int>* triangles) const {
  triangles->clear();
  if (empty()) return;
  std::vector<int> stack = {0};
  while (!stack.empty()) {
    const Node& n = nodes_[stack.back()];
    stack.pop_back();
    if (!Near(n.box, box, margin)) continue;
    if (n.triangle >= 0) {
      triangles->push_back(n.triangle);
    } else {
      stack.push_back(n.left);
      stack.push_back(n.right);
    }
  }
}

}  // namespace femreg
