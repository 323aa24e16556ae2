#include "solvers/backend.h"

#include "solvers/ceres/ceres_backend.h"
#include "solvers/fast/fast_backend.h"

namespace femreg {

std::unique_ptr<Backend> MakeBackend(const BackendOptions& options) {
  if (options.type == SolverBackend::kFast) {
    return std::make_unique<fast_backend::FastBackend>(options);
  }
  return std::make_unique<ceres_backend::CeresBackend>(options);
}

}  // namespace femreg
