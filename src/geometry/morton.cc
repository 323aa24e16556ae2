#include "geometry/morton.h"

#include <algorithm>
#include <cstdint>

namespace femreg {

namespace {
// The bits of v (21 of them) spread to every third bit: one coordinate of a Morton code.
uint64_t SpreadBits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}
}  // namespace

std::vector<int> MortonOrder(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& points) {
  const int n = static_cast<int>(points.rows());
  std::vector<uint64_t> code(static_cast<size_t>(n), 0);
  if (n > 0 && points.allFinite()) {
    const Eigen::RowVector3d lo = points.colwise().minCoeff();
    const Eigen::RowVector3d extent = (points.colwise().maxCoeff() - lo).cwiseMax(1e-300);
    for (int v = 0; v < n; ++v) {
      uint64_t c = 0;
      for (int d = 0; d < 3; ++d) {
        const double t = std::clamp((points(v, d) - lo[d]) / extent[d], 0.0, 1.0);
        c |= SpreadBits(static_cast<uint64_t>(t * ((1 << 21) - 1))) << d;
      }
      code[static_cast<size_t>(v)] = c;
    }
  }
  std::vector<int> along(static_cast<size_t>(n));
  for (int v = 0; v < n; ++v) along[static_cast<size_t>(v)] = v;
  std::stable_sort(along.begin(), along.end(),
                   [&](int a, int b) { return code[static_cast<size_t>(a)] < code[static_cast<size_t>(b)]; });
  return along;
}

}  // namespace femreg
