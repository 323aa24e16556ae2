// The fast back end: Gauss-Newton / Levenberg-Marquardt over a directly assembled sparse
// system, the robust losses by iterative reweighting. One generic assembler takes every
// block type of the energy layer: each block's gradient and Gauss-Newton blocks (energy/
// term.h's Linearize) are scattered into a fixed sparsity pattern, which starts from the
// problem's coupling (the meshes' tetrahedra) and widens once for blocks that couple other
// vertices (contacts between objects), so CHOLMOD's symbolic analysis is reused across
// iterations and frames until the topology changes. Blocks whose Jacobian is constant and
// whose set has no robust loss (the elastic elements with their rotations held, springs)
// are assembled once per Solve.
#ifndef FEMREG_SOLVERS_FAST_FAST_BACKEND_H_
#define FEMREG_SOLVERS_FAST_FAST_BACKEND_H_

#include <Eigen/SparseCore>
#include <memory>

#include "solvers/backend.h"

namespace femreg {
namespace fast_backend {

class FastBackend : public Backend {
 public:
  explicit FastBackend(const BackendOptions& options);
  ~FastBackend() override;
  SolverBackend type() const override { return SolverBackend::kFast; }
  SolveReport Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// y = H p for a symmetric H stored column-major with both triangles and full 3x3 vertex
// blocks (the three columns of a vertex share their row pattern), the back end's system;
// in parallel on `threads` from `parallel_from` vertices on (below, PCG's product alone
// does not pay for a team's start). Equal to Eigen's H * p up to round-off, the same on
// any thread count.
void BlockProduct(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& p, int threads,
                  Eigen::VectorXd* y, int parallel_from = 8192);

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_FAST_BACKEND_H_
