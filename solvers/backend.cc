#include "solvers/backend.h"

#include "solvers/ceres/ceres_backend.h"
#include "solvers/fast/fast_backend.h"

namespace femreg {

const char* ToString(StopReason reason) {
  switch (reason) {
    case StopReason::kNotRun: return "not_run";
    case StopReason::kGradient: return "gradient";
    case StopReason::kStep: return "step";
    case StopReason::kEnergy: return "energy";
    case StopReason::kPredicted: return "predicted_decrease";
    case StopReason::kNoDecrease: return "no_decrease";
    case StopReason::kMaxIterations: return "max_iterations";
    case StopReason::kTimeLimit: return "time_limit";
    case StopReason::kSolver: return "solver";
    case StopReason::kFailure: return "failure";
  }
  return "unknown";
}

std::unique_ptr<Backend> MakeBackend(const BackendOptions& options) {
  if (options.type == SolverBackend::kFast) {
    return std::make_unique<fast_backend::FastBackend>(options);
  }
  return std::make_unique<ceres_backend::CeresBackend>(options);
}

}  // namespace femreg
