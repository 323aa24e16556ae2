// femreg/forward.h - the forward quasi-static solve: clamps, prescribed displacements,
// gravity and nodal loads, Newton iterations on the consistent corotational tangent (the
// derivative of the element rotations included) with a line search, CHOLMOD.
#ifndef FEMREG_FORWARD_H_
#define FEMREG_FORWARD_H_

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/field_table.h"
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

// The matrix Newton solves with (the corotational model; the linear one always uses K).
enum class ForwardTangent {
  // sum_e R_e K_e R_e^T: the rotations held fixed. Positive semi-definite, but not the
  // derivative of the forces, so Newton converges only linearly.
  kWarped,
  // The consistent tangent with each element's negative twist eigenvalues clamped to 0
  // (CorotationalTangent, kPositiveSemiDefinite): always a descent direction, exact where
  // no element is compressed, linear convergence otherwise.
  kProjected,
  // The exact consistent tangent (the Hessian of the potential), quadratic convergence
  // near a stable equilibrium; when the assembled matrix is not positive definite (far
  // from it, or near a limit point), the iteration uses kProjected instead.
  kFull,
};
const char* ToString(ForwardTangent tangent);
bool FromString(const std::string& name, ForwardTangent* tangent);

struct ForwardOptions {
  int max_iterations = 100;          // Newton iterations per load step
  int load_steps = 1;                // loads and prescribed displacements applied in steps
  double relative_tolerance = 1e-8;  // stop when |free residual| <= tol * |external load|
  double absolute_tolerance = 1e-12; // ... or below this (N)
  double min_step = 1e-10;           // line search gives up below this step length
  ForwardTangent tangent = ForwardTangent::kFull;  // corotational model only
  // Watchdog: a full Newton step that raises the potential is still taken; if within this
  // many further iterations the potential has not dropped below the point before it, the
  // solve returns there and backtracks. 0 = a monotone line search only. Corotational
  // model without problem.potential only (the neo-Hookean energy, not quadratic in the
  // rotated frame, grows too fast along a rejected full step: from rest under a large load
  // the first step can leave elements so distorted that the next tangent is singular).
  int watchdog_steps = 2;
  // Threads for the element loops and for the BLAS under CHOLMOD (OpenBLAS is held to
  // this many during the solve); 0 = OpenMP's current default (omp_get_max_threads).
  int num_threads = 0;
  bool verbose = false;              // one line per iteration on stdout
  // The element the scene's objects are built with for their forward solves (femreg simulate,
  // calibrate, synth); SolveQuasiStatic takes the model built, not this. Unset: corotational,
  // and a nearly incompressible object may get the neo-Hookean element instead
  // (ChooseForwardElements in femreg/scene.h); set, even to corotational, every object keeps it.
  std::optional<ElasticModelType> model = std::nullopt;
  ElasticModelType Model() const { return model.value_or(ElasticModelType::kCorotational); }
  bool IsValid(std::string* error) const;
};

// The scene's `forward:` keys. The other members are the program's (femreg simulate's flags,
// the tools'), checked by IsValid by hand.
template <>
struct OptionFields<ForwardOptions> {
  static constexpr const char* kSection = "forward";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = ForwardOptions;
    v(&S::model, FieldInfo("model").Doc("corotational, linear or neo_hookean; None: corotational, and the "
                                         "neo-Hookean element for nearly incompressible objects"));
    v(&S::max_iterations, FieldInfo("max_iterations").AtLeast(1).Doc("Newton iterations per load step"));
    v(&S::load_steps, FieldInfo("load_steps").AtLeast(1).Doc("loads and prescribed displacements applied in steps"));
    v(&S::relative_tolerance, FieldInfo("tolerance")
                                  .Python("relative_tolerance")
                                  .Above(0)
                                  .Doc("stop when the free residual's norm is at most this times the external load's"));
    v(&S::absolute_tolerance, FieldInfo("absolute_tolerance").AtLeast(0).Doc("... or below this (N)"));
  }
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
  int iteration = 0;           // 0: the step's starting point; k: after k Newton steps
  double energy = 0.0;         // elastic energy minus work of the external loads (J)
  double residual_norm = 0.0;  // |free-dof force imbalance| (N)
  double step_length = 0.0;    // line-search step taken
  // The matrix of the Newton step that led here (kFull, or kProjected after a fallback).
  ForwardTangent tangent = ForwardTangent::kWarped;
};

// One load step: the loads and prescribed displacements scaled by load_factor.
struct ForwardLoadStep {
  int load_step = 0;         // 1-based
  double load_factor = 0.0;  // load_step / load_steps
  ForwardTermination termination = ForwardTermination::kNotRun;
  int iterations = 0;        // Newton iterations (factorizations that were solved with)
  // kFull: iterations where the full tangent was not positive definite and the projected
  // one was used.
  int projected_iterations = 0;
  int relaxed_steps = 0;      // full steps taken by the watchdog although the potential rose
  int watchdog_restarts = 0;  // ... that did not pay off (the solve went back)
  double initial_residual_norm = 0.0;  // N
  double final_residual_norm = 0.0;    // N
};

struct ForwardSummary {
  ForwardTermination termination = ForwardTermination::kNotRun;
  std::string message = "SolveQuasiStatic was not called.";
  std::vector<ForwardIteration> iterations;  // every load step's rows, in order
  std::vector<ForwardLoadStep> load_steps;
  int num_free_dofs = 0;
  double initial_residual_norm = 0.0;
  double final_residual_norm = 0.0;
  double final_energy = 0.0;
  double max_displacement = 0.0;  // m
  // Elements with det F <= 0 (inverted or flat) at the final state: the model stays defined
  // there (PolarRotation's sign fix), but its answer is not physical.
  int inverted_elements = 0;
  double total_time_s = 0.0;
  double factorization_time_s = 0.0;
  int num_threads = 0;            // threads the solve ran with
  std::string BriefReport() const;
  std::string FullReport() const;
  // Converged, or stopped at max_iterations in a finite state (Ceres' sense: a result
  // a caller may look at). Only termination == kConverged is an equilibrium.
  bool IsSolutionUsable() const;
  // Newton iterations of all load steps (rows minus each step's starting row).
  int NumNewtonIterations() const;
};

// Solves for the equilibrium of `model` (already built on `mesh`) under `problem`, starting
// from mesh->x, and writes the result to mesh->x. mesh->mass must be set when gravity is
// non-zero. The corotational model refreshes its rotations every iteration.
Status SolveQuasiStatic(const ForwardProblem& problem, const ForwardOptions& options,
                        ElasticModel* model, TetMesh* mesh, ForwardSummary* summary);

// The system Newton solves at positions x (#V by 3; clamped and prescribed vertices as
// given) under the full load of `problem`, for tests and tools: the residual (gradient of
// the potential minus the load, 3 #V) and the matrix the solver factorizes for `tangent`
// over the free DOFs (n by n, both triangles; free_dofs[i] is the DOF 3 v + axis of
// row i). With ForwardTangent::kFull it is the exact tangent even when indefinite.
// The contact potential, if any, is refreshed at x.
Status EvaluateForwardSystem(const ForwardProblem& problem, const ForwardOptions& options,
                             const ElasticModel& model, const TetMesh& mesh, const Vertices& x,
                             Eigen::VectorXd* residual, Eigen::SparseMatrix<double>* tangent,
                             std::vector<int>* free_dofs);

// The external forces on the mesh at positions x under the full load of `problem` (each #V
// by 3, N), from the terms of the solve's residual: e.g. the force a tool applies through its
// prescribed vertices, or the contacts' push. At an equilibrium (a converged solve's mesh.x)
// they sum to zero to within the solve's force imbalance, and so do their moments with the
// corotational and neo-Hookean models (energies that a rotation leaves unchanged).
struct ForwardForces {
  // By the supports: at every held vertex (clamped, prescribed, or in no element) the force
  // that holds it there, the gradient of the potential (elastic plus problem.potential) minus
  // the load; zero at the free vertices.
  Vertices reactions;
  // By problem.potential (e.g. contacts): minus its gradient, refreshed at x; zero without one.
  Vertices potential;
  // The nodal loads and gravity on the lumped masses.
  Vertices loads;
};
Status EvaluateForwardForces(const ForwardProblem& problem, const ForwardOptions& options,
                             const ElasticModel& model, const TetMesh& mesh, const Vertices& x,
                             ForwardForces* forces);

// The resultant of nodal forces (#V by 3, N) and their torque (N m) about the body's
// centroid: the mean of `positions` weighted by the lumped masses `mass` (#V). How the
// datasets' forces.csv and the register results' force columns report a body's forces.
struct ForceResultant {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
};
ForceResultant ResultantAboutCentroid(const Vertices& forces, const Vertices& positions,
                                      const Eigen::VectorXd& mass);

}  // namespace femreg

#endif  // FEMREG_FORWARD_H_
