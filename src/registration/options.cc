// Names of the registration enums and the validation of RegistrationOptions.
#include <cmath>
#include <sstream>
#include <string>

#include "femreg/option_fields.h"
#include "femreg/registration.h"

namespace femreg {
namespace {

// Sets *error to "field message (got value)" and returns false.
template <typename T>
bool Fail(std::string* error, const char* field, const char* message, const T& value) {
  if (error != nullptr) {
    std::ostringstream os;
    os << field << " " << message << " (got " << value << ")";
    *error = os.str();
  }
  return false;
}

std::string VectorString(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}

}  // namespace

const char* ToString(RobustLoss v) {
  switch (v) {
    case RobustLoss::kNone:
      return "none";
    case RobustLoss::kHuber:
      return "huber";
    case RobustLoss::kCauchy:
      return "cauchy";
    case RobustLoss::kTukey:
      return "tukey";
  }
  return "unknown";
}

const char* ToString(DataMetric v) {
  switch (v) {
    case DataMetric::kPointToPoint:
      return "point_to_point";
    case DataMetric::kPointToPlane:
      return "point_to_plane";
  }
  return "unknown";
}

const char* ToString(Regularizer v) {
  switch (v) {
    case Regularizer::kCorotational:
      return "corotational";
    case Regularizer::kLinear:
      return "linear";
    case Regularizer::kMassSpring:
      return "mass_spring";
    case Regularizer::kNone:
      return "none";
  }
  return "unknown";
}

const char* ToString(SolverBackend v) {
  switch (v) {
    case SolverBackend::kCeres:
      return "ceres";
    case SolverBackend::kFast:
      return "fast";
  }
  return "unknown";
}

const char* ToString(TrustRegion v) {
  switch (v) {
    case TrustRegion::kLevenbergMarquardt:
      return "levenberg_marquardt";
    case TrustRegion::kDogleg:
      return "dogleg";
  }
  return "unknown";
}

const char* ToString(LinearSolver v) {
  switch (v) {
    case LinearSolver::kSparseNormalCholesky:
      return "sparse_normal_cholesky";
    case LinearSolver::kConjugateGradients:
      return "conjugate_gradients";
  }
  return "unknown";
}

const char* ToString(Preconditioner v) {
  switch (v) {
    case Preconditioner::kAuto:
      return "auto";
    case Preconditioner::kFactor:
      return "factor";
    case Preconditioner::kMultigrid:
      return "multigrid";
  }
  return "unknown";
}

const char* ToString(TerminationType t) {
  switch (t) {
    case TerminationType::kNotRun:
      return "not_run";
    case TerminationType::kConverged:
      return "converged";
    case TerminationType::kMaxIterations:
      return "max_iterations";
    case TerminationType::kTimeBudget:
      return "time_budget";
    case TerminationType::kNoCorrespondences:
      return "no_correspondences";
    case TerminationType::kSolverFailure:
      return "solver_failure";
    case TerminationType::kInvalidInput:
      return "invalid_input";
    case TerminationType::kTooFewPoints:
      return "too_few_points";
    case TerminationType::kStalled:
      return "stalled";
  }
  return "unknown";
}

// Each FromString accepts exactly the names ToString prints.
const char* ToString(InitialPose v) {
  switch (v) {
    case InitialPose::kGiven:
      return "given";
    case InitialPose::kAuto:
      return "auto";
  }
  return "unknown";
}

namespace {
template <class Enum>
bool EnumFromString(const std::string& s, Enum* v) {
  for (Enum candidate : EnumValues<Enum>::kAll) {
    if (s == ToString(candidate)) {
      *v = candidate;
      return true;
    }
  }
  return false;
}
}  // namespace

bool FromString(const std::string& s, RobustLoss* v) { return EnumFromString(s, v); }
bool FromString(const std::string& s, DataMetric* v) { return EnumFromString(s, v); }
bool FromString(const std::string& s, Regularizer* v) { return EnumFromString(s, v); }
bool FromString(const std::string& s, SolverBackend* v) { return EnumFromString(s, v); }
bool FromString(const std::string& s, TrustRegion* v) { return EnumFromString(s, v); }
bool FromString(const std::string& s, LinearSolver* v) { return EnumFromString(s, v); }
bool FromString(const std::string& s, Preconditioner* v) { return EnumFromString(s, v); }
bool FromString(const std::string& s, InitialPose* v) { return EnumFromString(s, v); }

bool CameraOptions::IsValid(std::string* error) const {
  if (!CheckFieldRanges(*this, error)) return false;
  if ((target - position).norm() <= 0) {
    return Fail(error, "camera.target", "must differ from camera.position", VectorString(target));
  }
  if ((target - position).normalized().cross(up).norm() < 1e-6) {
    return Fail(error, "camera.up", "must not be parallel to the viewing direction", VectorString(up));
  }
  return true;
}

bool PreprocessOptions::IsValid(std::string* error) const {
  if (!CheckFieldRanges(*this, error)) return false;
  if (crop && (crop_min.array() > crop_max.array()).any()) {
    return Fail(error, "preprocess.crop.min", "must be <= crop.max in every coordinate",
                VectorString(crop_min) + " and " + VectorString(crop_max));
  }
  if (normal_neighbors > 0 && normal_neighbors < 3) {
    return Fail(error, "preprocess.normals.neighbors", "must be 0 (off) or >= 3",
                normal_neighbors);
  }
  return true;
}

bool DataTermOptions::IsValid(std::string* error) const {
  if (!model_to_cloud && !cloud_to_model) {
    return Fail(error, "data.model_to_cloud", "or data.cloud_to_model must be true",
                "both false");
  }
  return CheckFieldRanges(*this, error);
}

bool WeightOptions::IsValid(std::string* error) const {
  if (!CheckFieldRanges(*this, error)) return false;
  if (data == 0 && elastic == 0 && temporal == 0) {
    return Fail(error, "weights", "data, elastic and temporal must not all be 0", "0, 0, 0");
  }
  return true;
}

bool SolverOptions::IsValid(std::string* error) const {
  if (!CheckFieldRanges(*this, error)) return false;
  if (rigid_prealign && rigid_iterations < 1) {
    return Fail(error, "solver.rigid_iterations", "must be >= 1 when rigid_prealign is on",
                rigid_iterations);
  }
  return true;
}

bool ForceOptions::IsValid(std::string* error) const {
  if (!CheckFieldRanges(*this, error)) return false;
  // Without estimate, the frames forces.when_occluded switches may push only: friction bounds those.
  if (friction >= 0 && !pushing_only && !(!estimate && when_occluded && when_occluded_pushing_only)) {
    return Fail(error, "forces.friction",
                "bounds a pushing force's tangential part: set forces.pushing_only too (or, without "
                "forces.estimate, forces.when_occluded and forces.when_occluded_pushing_only)",
                friction);
  }
  return true;
}

bool FreeSpaceOptions::IsValid(std::string* error) const {
  return CheckFieldRanges(*this, error);
}

bool RegistrationOptions::IsValid(std::string* error) const {
  // The sub-structs already name their fields with their own prefix (camera., data., ...).
  if (!(camera.IsValid(error) && preprocess.IsValid(error) && data.IsValid(error) &&
        weights.IsValid(error) && solver.IsValid(error) && forces.IsValid(error) &&
        free_space.IsValid(error))) {
    return false;
  }
  if (forces.estimate && regularizer == Regularizer::kNone) {
    if (error) *error = "forces.estimate needs an elastic regularizer (regularizer: none has no forces)";
    return false;
  }
  if (solver.trust_region == TrustRegion::kDogleg &&
      solver.linear_solver == LinearSolver::kConjugateGradients) {
    if (error) {
      *error = "solver.trust_region must be levenberg_marquardt with linear_solver "
               "conjugate_gradients (dogleg needs an exact factorization: "
               "sparse_normal_cholesky)";
    }
    return false;
  }
  return true;
}

}  // namespace femreg
