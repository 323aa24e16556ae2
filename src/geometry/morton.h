// Points along a Morton (Z-order) curve through their bounding box: near points come out near in
// the order. The assembler cuts its thread regions along it; the mesher writes its elements in it
// (docs/notes/2026-11-30-element-order.md).
#ifndef FEMREG_GEOMETRY_MORTON_H_
#define FEMREG_GEOMETRY_MORTON_H_

#include <Eigen/Core>
#include <vector>

namespace femreg {

// The indices of the rows of `points` (#P by 3) in the curve's order, 21 bits per coordinate.
// Ties, and every point when one is not finite, keep their index order.
std::vector<int> MortonOrder(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& points);

}  // namespace femreg

#endif  // FEMREG_GEOMETRY_MORTON_H_
