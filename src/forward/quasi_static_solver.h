// The forward solve's state (forward.cc runs it, quasi_static_setup.cc sets it up): private to
// src/forward.
#ifndef FEMREG_FORWARD_QUASI_STATIC_SOLVER_H_
#define FEMREG_FORWARD_QUASI_STATIC_SOLVER_H_

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "energy/assembler.h"
#include "energy/nodal_volume.h"
#include "energy/problem.h"
#include "femreg/forward.h"
#include "parallel/stopwatch.h"
#include "parallel/threads.h"

namespace femreg {
namespace forward_internal {

// "5, 6, 4" (Newton iterations per load step), with "(2 projected)" where the full tangent
// fell back.
std::string IterationsPerStep(const std::vector<ForwardLoadStep>& steps);

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using Clock = std::chrono::steady_clock;

// CHOLMOD's supernodal LL^T with access to its rough reciprocal condition number
// min(diag L) / max(diag L), to tell a singular stiffness from an ill-conditioned one.
class Factorization : public Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> {
 public:
  Factorization() { cholmod().print = 0; }
  double ReciprocalCondition() {
    return m_cholmodFactor ? cholmod_rcond(m_cholmodFactor, &cholmod()) : 0.0;
  }
};

// Below this min(diag L) / max(diag L) the reduced stiffness is treated as singular: a rigid
// mode leaves a pivot at round-off level, about sqrt(eps) ~ 1e-8 of the largest.
constexpr double kMinReciprocalCondition = 1e-7;

// The matrices the reduced system can be filled with.
enum class ElementMatrix {
  kLinear,     // K
  kWarped,     // the Gauss-Newton one: R K R^T with the rotations of x held
  kProjected,  // the exact Hessian, projected element by element (energy/term.h)
  kExact,      // the exact Hessian of the potential
};

inline energy::Curvature CurvatureOf(ElementMatrix kind) {
  switch (kind) {
    case ElementMatrix::kExact:
      return energy::Curvature::kExact;
    case ElementMatrix::kProjected:
      return energy::Curvature::kProjected;
    default:
      return energy::Curvature::kGaussNewton;
  }
}

// The state of one solve: the energy (energy::Problem: the elements, and the nodal volume
// beside it), its assembler, the DOF numbering and the reduced system.
class QuasiStaticSolver {
 public:
  QuasiStaticSolver(const ForwardProblem& problem, const ForwardOptions& options,
                    const ElasticModel* model, TetMesh* mesh, ForwardSummary* summary)
      : problem_(problem),
        options_(options),
        model_(*model),
        mesh_(*mesh),
        summary_(*summary),
        threads_(ResolveThreadCount(options.num_threads)),
        assembler_(threads_) {
    summary_.num_threads = threads_;
  }

  // Checks the inputs; on error fills the summary and returns false.
  bool Validate();
  // Numbers the free DOFs, checks that every connected piece is held, builds the energy and,
  // with `reduced`, the reduced pattern and its analysis (what the Newton steps factorize).
  bool Setup(bool reduced = true);
  void Run();
  // For EvaluateForwardSystem (after Validate and Setup): the residual at x under the full
  // load and the reduced matrix of `tangent`, both triangles.
  void EvaluateSystem(const Vertices& x, ForwardTangent tangent, Eigen::VectorXd* residual,
                      Eigen::SparseMatrix<double>* matrix, std::vector<int>* free_dofs);
  // For EvaluateForwardForces (after Validate and Setup, reduced or not).
  void EvaluateForces(const Vertices& x, ForwardForces* forces);

 private:
  bool Fail(ForwardTermination termination, const std::string& message) {
    summary_.termination = termination;
    summary_.message = message;
    return false;
  }
  int nv() const { return mesh_.num_vertices(); }
  int nt() const { return model_.num_elements(); }
  bool linear() const { return model_.type() == ElasticModelType::kLinear; }
  bool neo_hookean() const { return model_.type() == ElasticModelType::kNeoHookean; }
  bool nodal_volume() const { return neo_hookean() && model_.nodal_volume(); }

  // The energy's terms: one block per element, the nodal volume beside them.
  void BuildEnergy(const std::vector<char>& held);
  // The reduced lower triangle's pattern from the assembler's, and where each entry's value is.
  void BuildReduced();
  // Elastic energy at x (the element energies with their rotations of x, and the nodal
  // volume's); its gradient into *gradient (3 #V).
  double Elastic(const Vertices& x, Eigen::VectorXd* gradient);
  // Assembles the matrix of `kind` at x (the assembler's H, all DOFs) and copies its free
  // lower triangle into matrix_.
  void Fill(const Vertices& x, ElementMatrix kind);
  // problem.potential's Hessian at x over the reduced DOFs (lower triangle).
  std::vector<Eigen::Triplet<double>> ReducedExtraHessian(const Vertices& x) const;
  // Factorizes matrix_ (+ extra); false with *error when not positive definite or
  // numerically singular.
  bool Factorize(const std::vector<Eigen::Triplet<double>>& extra, std::string* error);
  // Assembles the reduced tangent of options.tangent at x into matrix_ and factorizes it
  // (kFull: the exact tangent, or the projected one when that is not positive definite;
  // element_matrix_ says which). With problem.potential, its Hessian at x is added (the
  // pattern is then re-analyzed).
  bool AssembleAndFactorize(const Vertices& x);
  // problem.potential's energy at x (0 without one); adds its gradient when not null.
  double Extra(const Vertices& x, Eigen::VectorXd* gradient) const {
    return problem_.potential != nullptr ? problem_.potential->Evaluate(x, gradient) : 0.0;
  }
  // Total potential: elastic energy minus the work of `load` over the displacement.
  double Potential(double elastic, const Vertices& x, const Eigen::VectorXd& load) const;
  double FreeNorm(const Eigen::VectorXd& v) const;
  // The force imbalance that round-off alone leaves at positions x (N).
  double RoundoffFloor(const Vertices& x) const;
  void ScatterFree(const Eigen::VectorXd& reduced, double alpha, Vertices* x) const;

  // A point on a line search: positions, the elastic energy's gradient there, energies.
  struct Trial {
    Vertices x;
    Eigen::VectorXd gradient;
    double elastic = 0.0;
    double potential = 0.0;
  };
  // Backtracking (Armijo, safeguarded quadratic interpolation) from x along `step` with
  // directional derivative `slope` < 0, starting at *alpha. With may_relax, a full step
  // (alpha = 1) with a finite potential is accepted even when it raises the potential
  // (*relaxed; the caller's watchdog checks it later). False when no step >= min_step
  // decreases the potential; *trial then holds the last point tried.
  bool LineSearch(const Vertices& x, const Eigen::VectorXd& step, double slope, double potential,
                  double residual_norm, const Eigen::VectorXd& load, bool may_relax,
                  double* alpha, bool* relaxed, Trial* trial);
  // Moves the trial's state into x and gradient (the trial keeps the old ones).
  static void Accept(Trial* trial, Vertices* x, Eigen::VectorXd* gradient) {
    x->swap(trial->x);
    gradient->swap(trial->gradient);
  }

  const ForwardProblem& problem_;
  const ForwardOptions& options_;
  const ElasticModel& model_;
  TetMesh& mesh_;
  ForwardSummary& summary_;
  const int threads_;                // OpenMP threads of the element loops

  energy::Problem energy_;           // the elements, held vertices fixed
  std::unique_ptr<energy::NodalVolume> nodal_;  // neo-Hookean nodal volume, or null
  std::vector<Eigen::Matrix3d> rotations_;      // held by the elements for kWarped
  energy::Assembler assembler_;
  std::vector<int> free_index_;      // 3 #V: dof -> reduced index, or -1 when held
  std::vector<int> free_dofs_;       // reduced index -> dof
  SparseMatrix matrix_;              // reduced stiffness, lower triangle
  std::vector<int> reduced_at_;      // per entry of matrix_: its value's index in H
  Factorization factorization_;
  ElementMatrix element_matrix_ = ElementMatrix::kWarped;  // of the last factorization
  bool factorized_for_linear_ = false;
  bool analyzed_elastic_pattern_ = true;  // false after a potential's entries widened it
  Eigen::VectorXd full_load_;        // 3 #V external load at full scale
};

}  // namespace forward_internal
}  // namespace femreg

#endif  // FEMREG_FORWARD_QUASI_STATIC_SOLVER_H_
