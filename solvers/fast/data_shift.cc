#include "solvers/fast/data_shift.h"

#include <algorithm>
#include <cmath>

#include "energy/equilibrium.h"

namespace femreg {
namespace fast_backend {

std::vector<double> AddDataShift(const energy::Problem& problem, const Eigen::SparseMatrix<double>& H,
                                 Eigen::SparseMatrix<double>* K) {
  std::vector<double> before(K->valuePtr(), K->valuePtr() + K->nonZeros());
  const energy::Equilibrium& eq = *problem.equilibrium();
  double phi = 0.0;
  int free = 0;
  for (int v = 0; v < problem.num_vertices(); ++v) {
    if (eq.site[static_cast<size_t>(v)] != energy::ForceSite::kFree) continue;
    phi += eq.force_weight[static_cast<size_t>(v)];
    ++free;
  }
  const Eigen::VectorXd d = H.diagonal();
  double largest = 0.0;
  for (int c = 0; c < d.size(); ++c) {
    if (!problem.is_fixed(c / 3)) largest = std::max(largest, d[c]);
  }
  double h = 0.0;
  int observed = 0;
  for (int c = 0; c < d.size(); ++c) {
    if (problem.is_fixed(c / 3) || d[c] < 0.01 * largest) continue;
    h += d[c];
    ++observed;
  }
  if (free == 0 || observed == 0 || !(phi > 0.0) || !(h > 0.0)) return {};
  const double shift = 1.0 / std::sqrt((phi / free) * (h / observed));
  const int* outer = K->outerIndexPtr();
  const int* inner = K->innerIndexPtr();
  for (int c = 0; c < H.cols(); ++c) {
    if (problem.is_fixed(c / 3)) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(H, c); it; ++it) {
      const int r = static_cast<int>(it.row());
      if (problem.is_fixed(r / 3)) continue;
      const int* at = std::lower_bound(inner + outer[c], inner + outer[c + 1], r);
      if (at != inner + outer[c + 1] && *at == r) K->valuePtr()[at - inner] += shift * it.value();
    }
  }
  return before;
}

}  // namespace fast_backend
}  // namespace femreg
