// femreg/forward.h - the forward quasi-static solve: clamps, prescribed displacements,
// gravity and nodal loads, Newton-type iterations on the warped stiffness with CHOLMOD.
#ifndef FEMREG_FORWARD_H_
#define FEMREG_FORWARD_H_

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

// An energy added to the elastic one in a forward solve, e.g. contact penalties
// (collision.h's ContactPotential). The solver calls Refresh at the start of every Newton
// iteration (the active set may change there) and keeps it fixed within the line search.
class ForwardPotential {
 public:
  virtual ~ForwardPotential() = default;
  virtual void Refresh(const Vertices& x) = 0;
  // Energy at x (J); adds dE/dx to *gradient (3 #V, may be null).
  virtual double Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const = 0;
  // Adds a symmetric positive semi-definite approximation of d2E/dx2 as (dof, dof, value)
  // triplets over the 3 #V DOFs (both triangles).
  virtual void AddHessian(const Vertices& x, std::vector<Eigen::Triplet<double>>* triplets) const = 0;
};

struct ForwardProblem {
  std::vector<int> clamped;  // vertices held at their rest position
  // Vertices moved by a prescribed displacement from rest (m). A vertex listed here and
  // in `clamped` is an input error.
  std::vector<std::pair<int, Eigen::Vector3d>> prescribed;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // m/s^2, acts on the lumped masses
  std::vector<std::pair<int, Eigen::Vector3d>> nodal_loads;  // vertex, force (N)
  ForwardPotential* potential = nullptr;  // extra energy (not owned), e.g. contacts
};

struct ForwardOptions {
  int max_iterations = 100;          // Newton iterations per load step
  int load_steps = 1;                // loads and prescribed displacements applied in steps
  double relative_tolerance = 1e-8;  // stop when |free residual| <= tol * |external load|
  double absolute_tolerance = 1e-12; // ... or below this (N)
  double min_step = 1e-10;           // line search gives up below this step length
  bool verbose = false;              // one line per iteration on stdout
  bool IsValid(std::string* error) const;
};

enum class ForwardTermination {
  kNotRun,
  kConverged,
  kMaxIterations,
  kLineSearchFailed,
  kFactorizationFailed,  // e.g. not enough clamps: the stiffness is singular
  kInvalidInput,
};
const char* ToString(ForwardTermination termination);

struct ForwardIteration {
  int load_step = 0;
  int iteration = 0;
  double energy = 0.0;         // elastic energy minus work of the external loads (J)
  double residual_norm = 0.0;  // |free-dof force imbalance| (N)
  double step_length = 0.0;    // line-search step taken
};

struct ForwardSummary {
  ForwardTermination termination = ForwardTermination::kNotRun;
  std::string message = "SolveQuasiStatic was not called.";
  std::vector<ForwardIteration> iterations;
  int num_free_dofs = 0;
  double initial_residual_norm = 0.0;
  double final_residual_norm = 0.0;
  double final_energy = 0.0;
  double max_displacement = 0.0;  // m
  double total_time_s = 0.0;
  double factorization_time_s = 0.0;
  std::string BriefReport() const;
  std::string FullReport() const;
  bool IsSolutionUsable() const;
};

// Solves for the equilibrium of `model` (already built on `mesh`) under `problem`, starting
// from mesh->x, and writes the result to mesh->x. mesh->mass must be set when gravity is
// non-zero. The corotational model refreshes its rotations every iteration.
Status SolveQuasiStatic(const ForwardProblem& problem, const ForwardOptions& options,
                        ElasticModel* model, TetMesh* mesh, ForwardSummary* summary);

}  // namespace femreg

#endif  // FEMREG_FORWARD_H_
