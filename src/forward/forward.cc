// The forward quasi-static solve: Newton iterations on the exact Hessian of the potential
// (the consistent corotational tangent, or the stable neo-Hookean element's), with the exact
// gradient, a backtracking line search on the total potential (rotations recomputed at every
// trial point), load stepping, and clamped / prescribed DOFs eliminated. By default the exact
// Hessian is tried first and, when CHOLMOD finds it not positive definite, its element-wise
// PSD projection is used for that iteration. The energy is the energy layer's (one block per
// element, and with the neo-Hookean nodal volume energy::NodalVolume beside them), assembled
// by its assembler (energy/assembler.h); the free rows and columns of that system, lower
// triangle, are solved with CHOLMOD's supernodal Cholesky. The pattern is fixed, so the
// symbolic analysis is done once per solve.
#include "femreg/forward.h"

#include <Eigen/CholmodSupport>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>

#include "energy/assembler.h"
#include "energy/nodal_volume.h"
#include "energy/problem.h"
#include "parallel/signals.h"
#include "parallel/threads.h"

namespace femreg {

bool ForwardOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (max_iterations < 1) {
    os << "max_iterations must be >= 1 (got " << max_iterations << ")";
  } else if (load_steps < 1) {
    os << "load_steps must be >= 1 (got " << load_steps << ")";
  } else if (!(std::isfinite(relative_tolerance) && relative_tolerance >= 0)) {
    os << "relative_tolerance must be finite and >= 0 (got " << relative_tolerance << ")";
  } else if (!(std::isfinite(absolute_tolerance) && absolute_tolerance >= 0)) {
    os << "absolute_tolerance must be finite and >= 0 (got " << absolute_tolerance << ")";
  } else if (relative_tolerance == 0 && absolute_tolerance == 0) {
    os << "relative_tolerance and absolute_tolerance cannot both be 0";
  } else if (!(std::isfinite(min_step) && min_step > 0 && min_step < 1)) {
    os << "min_step must be in (0, 1) (got " << min_step << ")";
  } else if (watchdog_steps < 0) {
    os << "watchdog_steps must be >= 0 (got " << watchdog_steps << ")";
  } else if (num_threads < 0) {
    os << "num_threads must be >= 0 (got " << num_threads << "; 0 = OpenMP's default)";
  } else {
    return true;
  }
  if (error) *error = os.str();
  return false;
}

const char* ToString(ForwardTangent tangent) {
  switch (tangent) {
    case ForwardTangent::kWarped:
      return "warped";
    case ForwardTangent::kProjected:
      return "projected";
    case ForwardTangent::kFull:
      return "full";
  }
  return "unknown";
}

bool FromString(const std::string& name, ForwardTangent* tangent) {
  if (name == "warped") {
    *tangent = ForwardTangent::kWarped;
  } else if (name == "projected") {
    *tangent = ForwardTangent::kProjected;
  } else if (name == "full") {
    *tangent = ForwardTangent::kFull;
  } else {
    return false;
  }
  return true;
}

const char* ToString(ForwardTermination termination) {
  switch (termination) {
    case ForwardTermination::kNotRun:
      return "NOT_RUN";
    case ForwardTermination::kConverged:
      return "CONVERGED";
    case ForwardTermination::kMaxIterations:
      return "MAX_ITERATIONS";
    case ForwardTermination::kLineSearchFailed:
      return "LINE_SEARCH_FAILED";
    case ForwardTermination::kFactorizationFailed:
      return "FACTORIZATION_FAILED";
    case ForwardTermination::kInvalidInput:
      return "INVALID_INPUT";
  }
  return "UNKNOWN";
}

bool ForwardSummary::IsSolutionUsable() const {
  return termination == ForwardTermination::kConverged ||
         termination == ForwardTermination::kMaxIterations;
}

int ForwardSummary::NumNewtonIterations() const {
  int total = 0;
  for (const ForwardLoadStep& step : load_steps) total += step.iterations;
  return total;
}

namespace {

// "5, 6, 4" (Newton iterations per load step), with "(2 projected)" where the full tangent
// fell back.
std::string IterationsPerStep(const std::vector<ForwardLoadStep>& steps) {
  std::ostringstream os;
  for (size_t i = 0; i < steps.size(); ++i) {
    os << (i ? ", " : "") << steps[i].iterations;
    if (steps[i].projected_iterations > 0) os << " (" << steps[i].projected_iterations << " projected)";
    if (steps[i].termination != ForwardTermination::kConverged) {
      os << " " << ToString(steps[i].termination);
    }
  }
  return os.str();
}

}  // namespace

std::string ForwardSummary::BriefReport() const {
  std::ostringstream os;
  os << "Forward solve: " << ToString(termination) << ", " << NumNewtonIterations()
     << " Newton iterations in " << load_steps.size() << " load step"
     << (load_steps.size() == 1 ? "" : "s");
  if (!load_steps.empty()) os << " [" << IterationsPerStep(load_steps) << "]";
  os << ", |residual| " << std::scientific << std::setprecision(3) << initial_residual_norm
     << " -> " << final_residual_norm << " N, max displacement " << max_displacement << " m, ";
  if (inverted_elements > 0) os << inverted_elements << " inverted elements, ";
  os << std::fixed << std::setprecision(3) << total_time_s << " s";
  return os.str();
}

std::string ForwardSummary::FullReport() const {
  std::ostringstream os;
  os << "Forward quasi-static solve\n";
  os << "  free dofs            " << num_free_dofs << "\n";
  os << "  iter  step  it      potential (J)   |residual| (N)    step length\n";
  for (const ForwardIteration& it : iterations) {
    os << "  " << std::setw(4) << (&it - iterations.data()) << "  " << std::setw(4) << it.load_step
       << "  " << std::setw(2) << it.iteration << "  " << std::scientific << std::setprecision(6)
       << std::setw(16) << it.energy << "  " << std::setw(14) << std::setprecision(4)
       << it.residual_norm << "  " << std::setw(13) << it.step_length
       << (it.iteration > 0 && it.tangent == ForwardTangent::kProjected ? "  projected" : "")
       << "\n";
  }
  os << "  load step  factor  Newton its  projected  |residual| start -> end (N)  termination\n";
  for (const ForwardLoadStep& step : load_steps) {
    os << "  " << std::setw(9) << step.load_step << "  " << std::fixed << std::setprecision(3)
       << std::setw(6) << step.load_factor << "  " << std::setw(10) << step.iterations << "  "
       << std::setw(9) << step.projected_iterations << "  " << std::scientific
       << std::setprecision(3) << std::setw(10) << step.initial_residual_norm << " -> "
       << std::setw(10) << step.final_residual_norm << "        "
       << ToString(step.termination) << "\n";
  }
  os << std::scientific << std::setprecision(6);
  os << "  initial |residual|   " << initial_residual_norm << " N\n";
  os << "  final |residual|     " << final_residual_norm << " N\n";
  os << "  final potential      " << final_energy << " J\n";
  os << "  max displacement     " << max_displacement << " m\n";
  os << "  inverted elements    " << inverted_elements << "\n";
  os << std::fixed << std::setprecision(4);
  os << "  factorization time   " << factorization_time_s << " s\n";
  os << "  threads              " << num_threads << "\n";
  os << "  total time           " << total_time_s << " s\n";
  os << "  termination          " << ToString(termination) << ": " << message << "\n";
  return os.str();
}

namespace {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

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

energy::Curvature CurvatureOf(ElementMatrix kind) {
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
  // Numbers the free DOFs, checks that every connected piece is held, builds the energy and
  // the reduced pattern.
  bool Setup();
  void Run();
  // For EvaluateForwardSystem (after Validate and Setup): the residual at x under the full
  // load and the reduced matrix of `tangent`, both triangles.
  void EvaluateSystem(const Vertices& x, ForwardTangent tangent, Eigen::VectorXd* residual,
                      Eigen::SparseMatrix<double>* matrix, std::vector<int>* free_dofs);

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

bool QuasiStaticSolver::Validate() {
  std::string error;
  if (!options_.IsValid(&error)) return Fail(ForwardTermination::kInvalidInput, "options: " + error);
  std::ostringstream os;
  if (nv() == 0 || nt() == 0) {
    return Fail(ForwardTermination::kInvalidInput, "the mesh has no vertices or no elements");
  }
  if (mesh_.rest.rows() != mesh_.x.rows()) {
    os << "mesh.x has " << mesh_.x.rows() << " rows, mesh.rest has " << mesh_.rest.rows();
    return Fail(ForwardTermination::kInvalidInput, os.str());
  }
  if (nt() != mesh_.num_tets()) {
    os << "the elastic model has " << nt() << " elements but the mesh has " << mesh_.num_tets()
       << " (was ElasticModel::Build called on this mesh?)";
    return Fail(ForwardTermination::kInvalidInput, os.str());
  }
  if (model_.tets().size() > 0 &&
      (model_.tets().minCoeff() < 0 || model_.tets().maxCoeff() >= nv())) {
    return Fail(ForwardTermination::kInvalidInput,
                "the elastic model refers to vertices outside the mesh");
  }
  if (!mesh_.x.allFinite() || !mesh_.rest.allFinite()) {
    return Fail(ForwardTermination::kInvalidInput, "mesh.x or mesh.rest has a non-finite entry");
  }
  if (!problem_.gravity.allFinite()) {
    return Fail(ForwardTermination::kInvalidInput, "problem.gravity is not finite");
  }
  std::vector<char> held(nv(), 0);
  for (int v : problem_.clamped) {
    if (v < 0 || v >= nv()) {
      os << "problem.clamped: vertex " << v << " is outside 0.." << nv() - 1;
      return Fail(ForwardTermination::kInvalidInput, os.str());
    }
    held[v] = 1;
  }
  for (const auto& p : problem_.prescribed) {
    if (p.first < 0 || p.first >= nv()) {
      os << "problem.prescribed: vertex " << p.first << " is outside 0.." << nv() - 1;
      return Fail(ForwardTermination::kInvalidInput, os.str());
    }
    if (!p.second.allFinite()) {
      os << "problem.prescribed: the displacement of vertex " << p.first << " is not finite";
      return Fail(ForwardTermination::kInvalidInput, os.str());
    }
    if (held[p.first] == 1) {
      os << "problem.prescribed: vertex " << p.first << " is also clamped";
      return Fail(ForwardTermination::kInvalidInput, os.str());
    }
    if (held[p.first] == 2) {
      os << "problem.prescribed: vertex " << p.first << " is listed twice";
      return Fail(ForwardTermination::kInvalidInput, os.str());
    }
    held[p.first] = 2;
  }
  full_load_ = Eigen::VectorXd::Zero(3 * nv());
  for (const auto& l : problem_.nodal_loads) {
    if (l.first < 0 || l.first >= nv()) {
      os << "problem.nodal_loads: vertex " << l.first << " is outside 0.." << nv() - 1;
      return Fail(ForwardTermination::kInvalidInput, os.str());
    }
    if (!l.second.allFinite()) {
      os << "problem.nodal_loads: the load on vertex " << l.first << " is not finite";
      return Fail(ForwardTermination::kInvalidInput, os.str());
    }
    full_load_.segment<3>(3 * l.first) += l.second;
  }
  if (problem_.gravity.squaredNorm() > 0) {
    if (mesh_.mass.size() != nv() || !mesh_.mass.allFinite() || mesh_.mass.minCoeff() < 0) {
      return Fail(ForwardTermination::kInvalidInput,
                  "gravity is set but mesh.mass is missing, negative or not finite (call "
                  "ComputeLumpedMasses)");
    }
    for (int v = 0; v < nv(); ++v) full_load_.segment<3>(3 * v) += mesh_.mass(v) * problem_.gravity;
  }
  return true;
}

bool QuasiStaticSolver::Setup() {
  const Tets& tets = model_.tets();
  // Vertex -> element adjacency of the model's elements.
  std::vector<int> element_offsets(nv() + 1, 0), element_slots;
  for (int e = 0; e < nt(); ++e)
    for (int k = 0; k < 4; ++k) ++element_offsets[tets(e, k) + 1];
  for (int v = 0; v < nv(); ++v) element_offsets[v + 1] += element_offsets[v];
  element_slots.assign(element_offsets[nv()], 0);
  {
    std::vector<int> fill(element_offsets.begin(), element_offsets.end() - 1);
    for (int e = 0; e < nt(); ++e)
      for (int k = 0; k < 4; ++k) element_slots[fill[tets(e, k)]++] = 4 * e + k;
  }

  // Held vertices: clamped, prescribed, and vertices no element uses (they cannot move).
  std::vector<char> held(nv(), 0);
  for (int v : problem_.clamped) held[v] = 1;
  for (const auto& p : problem_.prescribed) held[p.first] = 1;
  for (int v = 0; v < nv(); ++v) {
    if (element_offsets[v] == element_offsets[v + 1]) held[v] = 1;
  }

  // Every vertex-connected piece must hold at least three non-collinear vertices, or it
  // has a rigid motion and the stiffness is singular.
  std::vector<int> component(nt(), -1);
  std::vector<int> listed(nv(), 0);  // component + 1 that listed a held vertex
  int num_components = 0;
  for (int seed = 0; seed < nt(); ++seed) {
    if (component[seed] >= 0) continue;
    std::vector<int> stack = {seed};
    component[seed] = num_components;
    std::vector<int> held_vertices;
    int size = 0;
    while (!stack.empty()) {
      const int e = stack.back();
      stack.pop_back();
      ++size;
      for (int k = 0; k < 4; ++k) {
        const int v = tets(e, k);
        if (held[v] && listed[v] != num_components + 1) {
          listed[v] = num_components + 1;
          held_vertices.push_back(v);
        }
        for (int s = element_offsets[v]; s < element_offsets[v + 1]; ++s) {
          const int other = element_slots[s] / 4;
          if (component[other] < 0) {
            component[other] = num_components;
            stack.push_back(other);
          }
        }
      }
    }
    // Rank of the held vertices' rest positions about their centroid (2 = not collinear).
    int rank = 0;
    if (!held_vertices.empty()) {
      Eigen::MatrixXd P(held_vertices.size(), 3);
      for (size_t i = 0; i < held_vertices.size(); ++i) P.row(i) = mesh_.rest.row(held_vertices[i]);
      P.rowwise() -= P.colwise().mean();
      const double scale = P.cwiseAbs().maxCoeff();
      if (scale > 0) {
        Eigen::JacobiSVD<Eigen::MatrixXd> svd(P / scale);
        for (int i = 0; i < svd.singularValues().size(); ++i)
          if (svd.singularValues()(i) > 1e-9 * std::sqrt(double(held_vertices.size()))) ++rank;
      }
    }
    if (rank < 2) {
      std::ostringstream os;
      os << "the stiffness is singular: a connected piece of " << size << " elements (element "
         << seed << ", vertex " << tets(seed, 0) << ") ";
      if (held_vertices.empty()) {
        os << "has no clamped or prescribed vertex, so it floats freely";
      } else {
        os << "is held only at " << held_vertices.size()
           << " collinear vertices, so it can rotate; clamp at least 3 non-collinear vertices";
      }
      return Fail(ForwardTermination::kFactorizationFailed, os.str());
    }
    ++num_components;
  }

  free_index_.assign(3 * nv(), -1);
  free_dofs_.clear();
  for (int v = 0; v < nv(); ++v) {
    if (held[v]) continue;
    for (int i = 0; i < 3; ++i) {
      free_index_[3 * v + i] = static_cast<int>(free_dofs_.size());
      free_dofs_.push_back(3 * v + i);
    }
  }
  summary_.num_free_dofs = static_cast<int>(free_dofs_.size());
  BuildEnergy(held);
  if (free_dofs_.empty()) return true;
  BuildReduced();
  const auto start = Clock::now();
  {
    const KeepSignalHandlers keep;  // METIS's signal() calls (parallel/signals.h)
    factorization_.analyzePattern(matrix_);
  }
  summary_.factorization_time_s += Seconds(start);
  if (factorization_.info() != Eigen::Success) {
    return Fail(ForwardTermination::kFactorizationFailed,
                "CHOLMOD could not analyze the stiffness pattern (out of memory?)");
  }
  return true;
}

void QuasiStaticSolver::BuildEnergy(const std::vector<char>& held) {
  const Tets& tets = model_.tets();
  energy_.Reset(nv());
  std::vector<std::array<int, 4>> cells(nt());
  for (int e = 0; e < nt(); ++e)
    for (int k = 0; k < 4; ++k) cells[e][k] = tets(e, k);
  energy_.SetCoupling(std::move(cells));
  energy_.fixed().assign(held.begin(), held.end());
  rotations_.assign(nt(), Eigen::Matrix3d::Identity());
  if (neo_hookean()) {
    auto* blocks = energy_.AddSet<energy::NeoHookeanElement>(energy::TermGroup::kElastic).mutable_blocks();
    std::vector<const ElementRest*> rests(nt());
    for (int e = 0; e < nt(); ++e) {
      energy::NeoHookeanElement b;
      for (int k = 0; k < 4; ++k) b.vertices[k] = tets(e, k);
      b.rest = rests[e] = &model_.rest(e);
      b.deviatoric = nodal_volume();
      blocks->push_back(b);
    }
    if (nodal_volume()) {
      nodal_ = std::make_unique<energy::NodalVolume>();
      nodal_->Build(tets, rests, nv(), threads_);
    }
  } else {
    auto* blocks = energy_.AddSet<energy::ElasticElement>(energy::TermGroup::kElastic).mutable_blocks();
    for (int e = 0; e < nt(); ++e) {
      energy::ElasticElement b;
      for (int k = 0; k < 4; ++k) b.vertices[k] = tets(e, k);
      b.rest = &model_.rest(e);
      b.rotation = &rotations_[e];
      b.corotational = !linear();
      blocks->push_back(b);
    }
  }
  assembler_.Prepare(energy_, mesh_.x, nodal_ ? nodal_->Pairs() : std::vector<std::pair<int, int>>());
}

void QuasiStaticSolver::BuildReduced() {
  // H's free rows and columns, lower triangle: the reduced index grows with the DOF, so H's
  // sorted rows stay sorted.
  const SparseMatrix& H = assembler_.H();
  const int n = static_cast<int>(free_dofs_.size());
  matrix_.resize(n, n);
  std::vector<int> outer(n + 1, 0), inner;
  reduced_at_.clear();
  for (int c = 0; c < n; ++c) {
    const int column = free_dofs_[c];
    for (SparseMatrix::InnerIterator it(H, column); it; ++it) {
      const int r = free_index_[it.row()];
      if (r < c) continue;  // held, or above the diagonal
      inner.push_back(r);
      reduced_at_.push_back(static_cast<int>(&it.value() - H.valuePtr()));
    }
    outer[c + 1] = static_cast<int>(inner.size());
  }
  matrix_.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), matrix_.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), matrix_.innerIndexPtr());
  std::fill(matrix_.valuePtr(), matrix_.valuePtr() + inner.size(), 0.0);
}

double QuasiStaticSolver::Elastic(const Vertices& x, Eigen::VectorXd* gradient) {
  double energy = assembler_.AssembleSecondOrder(energy_, x, energy::Curvature::kExact,
                                                 /*with_hessian=*/false, gradient);
  if (nodal_) energy += nodal_->Evaluate(x, gradient);
  return energy;
}

void QuasiStaticSolver::Fill(const Vertices& x, ElementMatrix kind) {
  if (neo_hookean() && kind == ElementMatrix::kWarped) kind = ElementMatrix::kProjected;  // no warped matrix
  if (kind == ElementMatrix::kWarped && !linear()) {  // the Gauss-Newton matrix holds R(x)
    const Tets& tets = model_.tets();
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (int e = 0; e < nt(); ++e) {
      Eigen::Matrix<double, 3, 4> xm;
      for (int k = 0; k < 4; ++k) xm.col(k) = x.row(tets(e, k)).transpose();
      rotations_[e] = PolarRotation(DeformationGradient(xm, model_.rest(e).dm_inv));
    }
  }
  Eigen::VectorXd gradient;
  assembler_.AssembleSecondOrder(energy_, x, CurvatureOf(kind), /*with_hessian=*/true, &gradient);
  if (nodal_) {
    nodal_->AddHessian(x, kind == ElementMatrix::kExact ? energy::Curvature::kExact : energy::Curvature::kProjected,
                       &assembler_);
  }
  const double* from = assembler_.H().valuePtr();
  double* to = matrix_.valuePtr();
  for (size_t k = 0; k < reduced_at_.size(); ++k) to[k] = from[reduced_at_[k]];
}

std::vector<Eigen::Triplet<double>> QuasiStaticSolver::ReducedExtraHessian(const Vertices& x) const {
  std::vector<Eigen::Triplet<double>> extra, reduced;
  if (problem_.potential != nullptr) problem_.potential->AddHessian(x, &extra);
  for (const auto& t : extra) {
    const int r = free_index_[t.row()], c = free_index_[t.col()];
    if (r >= 0 && c >= 0 && r >= c) reduced.emplace_back(r, c, t.value());
  }
  return reduced;
}

bool QuasiStaticSolver::Factorize(const std::vector<Eigen::Triplet<double>>& extra,
                                  std::string* error) {
  const auto start = Clock::now();
  if (!extra.empty()) {
    SparseMatrix contact(matrix_.rows(), matrix_.cols());
    contact.setFromTriplets(extra.begin(), extra.end());
    const SparseMatrix sum = matrix_ + contact;
    {
      const KeepSignalHandlers keep;
      factorization_.analyzePattern(sum);
    }
    // CHOLMOD's own OpenMP teams on one thread, its BLAS on threads_ (as in the fast back end,
    // and for the same reason: faster (docs/notes/2026-11-28-figures-from-code-comments.md)).
    WithThreadLimit(1, [&] { factorization_.factorize(sum); });
    analyzed_elastic_pattern_ = false;
  } else {
    if (!analyzed_elastic_pattern_) {
      const KeepSignalHandlers keep;
      factorization_.analyzePattern(matrix_);
    }
    analyzed_elastic_pattern_ = true;
    WithThreadLimit(1, [&] { factorization_.factorize(matrix_); });
  }
  summary_.factorization_time_s += Seconds(start);
  if (factorization_.info() != Eigen::Success) {
    *error = "CHOLMOD: the reduced stiffness is not positive definite (too few clamps, or a "
             "mechanism such as elements joined only at an edge or a vertex)";
    return false;
  }
  const double rcond = factorization_.ReciprocalCondition();
  if (!(rcond > kMinReciprocalCondition)) {
    std::ostringstream os;
    os << "the reduced stiffness is numerically singular (CHOLMOD min/max pivot " << rcond
       << "): too few clamps, or a mechanism such as elements joined only at an edge or a vertex";
    *error = os.str();
    return false;
  }
  return true;
}

bool QuasiStaticSolver::AssembleAndFactorize(const Vertices& x) {
  if (linear() && factorized_for_linear_ && problem_.potential == nullptr) return true;  // K does not change
  const std::vector<Eigen::Triplet<double>> extra = ReducedExtraHessian(x);
  std::string error;
  if (!linear() && options_.tangent == ForwardTangent::kFull) {
    // The exact tangent when it is positive definite (near a stable equilibrium); a limit
    // point or a compressed state far from it makes it indefinite (or nearly singular).
    Fill(x, ElementMatrix::kExact);
    if (Factorize(extra, &error)) {
      element_matrix_ = ElementMatrix::kExact;
      return true;
    }
  }
  ElementMatrix kind = ElementMatrix::kLinear;
  if (!linear()) {
    kind = options_.tangent == ForwardTangent::kWarped ? ElementMatrix::kWarped
                                                        : ElementMatrix::kProjected;
  }
  // The projected tangent is the warped stiffness plus PSD terms: when it is singular, so
  // is the warped one, and the problem has a mechanism.
  Fill(x, kind);
  if (!Factorize(extra, &error)) return Fail(ForwardTermination::kFactorizationFailed, error);
  element_matrix_ = kind;
  factorized_for_linear_ = linear();
  return true;
}

void QuasiStaticSolver::EvaluateSystem(const Vertices& x, ForwardTangent tangent,
                                       Eigen::VectorXd* residual,
                                       Eigen::SparseMatrix<double>* matrix,
                                       std::vector<int>* free_dofs) {
  Eigen::VectorXd gradient;
  Elastic(x, &gradient);
  if (problem_.potential != nullptr) problem_.potential->Refresh(x);
  Extra(x, &gradient);
  *residual = gradient - full_load_;
  *free_dofs = free_dofs_;
  const int n = static_cast<int>(free_dofs_.size());
  if (n == 0) {
    matrix->resize(0, 0);
    return;
  }
  ElementMatrix kind = ElementMatrix::kLinear;
  if (!linear()) {
    kind = tangent == ForwardTangent::kWarped      ? ElementMatrix::kWarped
           : tangent == ForwardTangent::kProjected ? ElementMatrix::kProjected
                                                   : ElementMatrix::kExact;
  }
  Fill(x, kind);
  SparseMatrix lower = matrix_;
  const std::vector<Eigen::Triplet<double>> extra = ReducedExtraHessian(x);
  if (!extra.empty()) {
    SparseMatrix contact(n, n);
    contact.setFromTriplets(extra.begin(), extra.end());
    lower += contact;
  }
  SparseMatrix diagonal(n, n);
  std::vector<Eigen::Triplet<double>> d;
  for (int col = 0; col < n; ++col)
    for (SparseMatrix::InnerIterator it(lower, col); it; ++it)
      if (it.row() == col) d.emplace_back(col, col, it.value());
  diagonal.setFromTriplets(d.begin(), d.end());
  *matrix = lower + SparseMatrix(lower.transpose()) - diagonal;
}

double QuasiStaticSolver::Potential(double elastic, const Vertices& x,
                                    const Eigen::VectorXd& load) const {
  const Eigen::Map<const Eigen::VectorXd> xv(x.data(), 3 * nv());
  const Eigen::Map<const Eigen::VectorXd> Xv(mesh_.rest.data(), 3 * nv());
  return elastic - load.dot(xv - Xv);
}

double QuasiStaticSolver::RoundoffFloor(const Vertices& x) const {
  // The forces are sums of K_e x_e terms: their round-off is about eps |K| |x| per DOF.
  double max_diagonal = 0.0;
  for (int e = 0; e < nt(); ++e) max_diagonal = std::max(max_diagonal, model_.rest(e).K.diagonal().maxCoeff());
  const double max_coordinate = std::max(x.cwiseAbs().maxCoeff(), mesh_.rest.cwiseAbs().maxCoeff());
  return 64.0 * std::numeric_limits<double>::epsilon() * max_diagonal * max_coordinate *
         std::sqrt(static_cast<double>(free_dofs_.size()));
}

double QuasiStaticSolver::FreeNorm(const Eigen::VectorXd& v) const {
  double sum = 0.0;
  for (int d : free_dofs_) sum += v(d) * v(d);
  return std::sqrt(sum);
}

void QuasiStaticSolver::ScatterFree(const Eigen::VectorXd& reduced, double alpha,
                                    Vertices* x) const {
  double* data = x->data();
  for (size_t i = 0; i < free_dofs_.size(); ++i) data[free_dofs_[i]] += alpha * reduced(i);
}

bool QuasiStaticSolver::LineSearch(const Vertices& x, const Eigen::VectorXd& step, double slope,
                                   double potential, double residual_norm,
                                   const Eigen::VectorXd& load, bool may_relax, double* alpha,
                                   bool* relaxed, Trial* trial) {
  *relaxed = false;
  Eigen::VectorXd trial_gradient;
  while (*alpha >= options_.min_step) {
    trial->x = x;
    ScatterFree(step, *alpha, &trial->x);
    trial->elastic = Elastic(trial->x, &trial->gradient);
    trial->potential = Potential(trial->elastic, trial->x, load) + Extra(trial->x, nullptr);
    const double value = trial->potential;
    if (std::isfinite(value)) {
      if (value <= potential + 1e-4 * *alpha * slope) return true;
      // Near the solution the decrease drowns in round-off of the energy: accept a step
      // that does not raise the potential beyond that noise and reduces the force imbalance.
      const double noise = 1e-12 * (std::abs(trial->elastic) + std::abs(value)) +
                           std::numeric_limits<double>::min();
      if (value - potential <= noise) {
        trial_gradient = trial->gradient;
        Extra(trial->x, &trial_gradient);
        if (FreeNorm(trial_gradient - load) < residual_norm) return true;
      }
      if (may_relax && *alpha == 1.0) {
        *relaxed = true;
        return true;
      }
    }
    // Safeguarded quadratic interpolation of the potential along the step.
    double next = 0.5 * *alpha;
    if (std::isfinite(value)) {
      const double denom = 2.0 * (value - potential - slope * *alpha);
      if (denom > 0) next = std::clamp(-slope * *alpha * *alpha / denom, 0.1 * *alpha, 0.5 * *alpha);
    }
    *alpha = next;
  }
  return false;
}

void QuasiStaticSolver::Run() {
  Vertices x = mesh_.x;
  for (int v : problem_.clamped) x.row(v) = mesh_.rest.row(v);
  Eigen::VectorXd elastic_gradient;  // of the elastic energy at x
  Trial trial;
  Eigen::VectorXd gradient, residual(3 * nv()), load(3 * nv());
  Eigen::VectorXd rhs(free_dofs_.size()), step(free_dofs_.size());
  // The watchdog (Chamberlain et al. 1982): when the full Newton step raises the potential,
  // take it anyway; if within options.watchdog_steps further iterations (full steps too) the
  // potential has not dropped below the point before it (the reference), return there and
  // backtrack. A slender or nearly incompressible body makes the full step
  // from a rotating configuration stretch stiff directions that are curved in x: the
  // potential rises although the next iterate lands next to the solution (the Maratos
  // effect), and a monotone search would crawl with short steps instead. Contact potentials
  // change their active set per iteration, so their potentials are not compared across
  // iterations: no watchdog with problem.potential.
  struct Watchdog {
    bool active = false;
    int steps = 0;  // iterations since the reference
    Vertices x;
    Eigen::VectorXd gradient;
    double elastic = 0.0, potential = 0.0, residual_norm = 0.0;
    Eigen::VectorXd step;
    double slope = 0.0;
    double full_step_potential = 0.0;  // at reference + step
  } watch;
  const bool watchdog_allowed =
      options_.watchdog_steps > 0 && model_.type() == ElasticModelType::kCorotational &&
      problem_.potential == nullptr;
  bool have_initial = false;
  double reference = 0.0;  // force scale of the relative tolerance
  double potential = 0.0, residual_norm = 0.0;

  double tolerance = 0.0;  // N, of the current iteration
  summary_.termination = ForwardTermination::kConverged;
  summary_.message = "converged";
  for (int load_step = 1; load_step <= options_.load_steps; ++load_step) {
    const double scale = static_cast<double>(load_step) / options_.load_steps;
    load = scale * full_load_;
    ForwardLoadStep record;
    record.load_step = load_step;
    record.load_factor = scale;
    // A factorization failure ends the solve; its step is reported as such.
    auto fail_step = [&] {
      record.termination = summary_.termination;
      record.final_residual_norm = residual_norm;
      summary_.load_steps.push_back(record);
    };

    // Move the prescribed vertices; predict the free ones with the current stiffness
    // (K_ff dx_f = -K_fp dx_p), so that elements next to them are not crushed.
    if (!problem_.prescribed.empty()) {
      Vertices delta = Vertices::Zero(nv(), 3);
      bool moved = false;
      for (const auto& p : problem_.prescribed) {
        delta.row(p.first) = (mesh_.rest.row(p.first) + scale * p.second.transpose()) - x.row(p.first);
        moved = moved || delta.row(p.first).squaredNorm() > 0;
      }
      if (moved && !free_dofs_.empty()) {
        if (!AssembleAndFactorize(x)) return fail_step();
        // The coupling with the matrix just factorized (the assembler's, over all DOFs).
        const Eigen::Map<const Eigen::VectorXd> moved_dofs(delta.data(), 3 * nv());
        const Eigen::VectorXd coupling = assembler_.H() * moved_dofs;
        for (size_t i = 0; i < free_dofs_.size(); ++i) rhs(i) = -coupling(free_dofs_[i]);
        step = factorization_.solve(rhs);
        if (step.allFinite()) ScatterFree(step, 1.0, &x);
      }
      x += delta;
    }

    double elastic = Elastic(x, &elastic_gradient);
    gradient = elastic_gradient;
    residual = gradient - load;
    potential = Potential(elastic, x, load);
    residual_norm = FreeNorm(residual);
    if (!have_initial) {
      summary_.initial_residual_norm = residual_norm;
      reference = residual_norm;
      have_initial = true;
    }

    double step_length = 0.0;
    watch.active = false;
    ForwardTangent step_tangent = options_.tangent;
    ForwardTermination step_result = ForwardTermination::kMaxIterations;
    for (int iteration = 0;; ++iteration) {
      if (problem_.potential != nullptr) {  // e.g. contacts: refreshed per Newton iteration
        problem_.potential->Refresh(x);
        gradient = elastic_gradient;
        potential = Potential(elastic, x, load) + Extra(x, &gradient);
        residual = gradient - load;
        residual_norm = FreeNorm(residual);
      }
      // Reference force: external loads, support reactions, and the first imbalance.
      double reaction = 0.0;
      for (int d = 0; d < 3 * nv(); ++d)
        if (free_index_[d] < 0) reaction += residual(d) * residual(d);
      reference = std::max({reference, load.norm(), std::sqrt(reaction)});
      summary_.iterations.push_back(
          {load_step, iteration, potential, residual_norm, step_length, step_tangent});
      if (iteration == 0) record.initial_residual_norm = residual_norm;
      tolerance = std::max({options_.absolute_tolerance, options_.relative_tolerance * reference,
                            RoundoffFloor(x)});
      if (options_.verbose) {
        std::printf("forward step %d iter %3d  potential %+.9e  |r| %.3e  alpha %.3g%s\n",
                    load_step, iteration, potential, residual_norm, step_length,
                    iteration > 0 && step_tangent == ForwardTangent::kProjected &&
                            options_.tangent == ForwardTangent::kFull
                        ? "  (projected)"
                        : "");
      }
      if (free_dofs_.empty() || residual_norm <= tolerance) {
        step_result = ForwardTermination::kConverged;
        break;
      }
      if (iteration >= options_.max_iterations) break;

      if (!AssembleAndFactorize(x)) return fail_step();
      ++record.iterations;
      step_tangent = element_matrix_ == ElementMatrix::kExact       ? ForwardTangent::kFull
                     : element_matrix_ == ElementMatrix::kProjected ? ForwardTangent::kProjected
                                                                    : ForwardTangent::kWarped;
      if (options_.tangent == ForwardTangent::kFull && step_tangent == ForwardTangent::kProjected) {
        ++record.projected_iterations;
      }
      for (size_t i = 0; i < free_dofs_.size(); ++i) rhs(i) = -residual(free_dofs_[i]);
      step = factorization_.solve(rhs);
      if (!step.allFinite()) {
        Fail(ForwardTermination::kFactorizationFailed,
             "the Newton step is not finite: the reduced stiffness is singular");
        return fail_step();
      }
      const double slope = -rhs.dot(step);  // directional derivative, < 0

      // Line search on the total potential, rotations recomputed at every trial point.
      double alpha = 1.0;
      bool relaxed = false;
      const bool may_relax = watchdog_allowed &&
                             (!watch.active || watch.steps <= options_.watchdog_steps);
      if (!LineSearch(x, step, slope, potential, residual_norm, load, may_relax, &alpha,
                      &relaxed, &trial)) {
        step_result = ForwardTermination::kLineSearchFailed;
        break;
      }
      if (relaxed) {
        ++record.relaxed_steps;
        if (!watch.active) {  // the last accepted point becomes the watchdog's reference
          watch.active = true;
          watch.steps = 0;
          watch.x = x;
          watch.gradient = elastic_gradient;
          watch.elastic = elastic;
          watch.potential = potential;
          watch.residual_norm = residual_norm;
          watch.step = step;
          watch.slope = slope;
          watch.full_step_potential = trial.potential;
        }
      }
      Accept(&trial, &x, &elastic_gradient);
      elastic = trial.elastic;
      potential = trial.potential;
      gradient = elastic_gradient;
      Extra(x, &gradient);
      residual = gradient - load;
      residual_norm = FreeNorm(residual);
      step_length = alpha;

      if (watch.active) {
        ++watch.steps;
        if (potential <= watch.potential + 1e-4 * watch.slope || residual_norm <= tolerance) {
          watch.active = false;  // the relaxed steps paid off (or reached an equilibrium)
        } else if (watch.steps > options_.watchdog_steps) {
          // They did not: back to the reference, and the monotone search along its step
          // (the full step there is known to fail, so start from the interpolated length).
          watch.active = false;
          ++record.watchdog_restarts;
          x = watch.x;
          elastic_gradient = watch.gradient;
          elastic = watch.elastic;
          potential = watch.potential;
          residual_norm = watch.residual_norm;
          double start = 0.5;
          const double denom = 2.0 * (watch.full_step_potential - potential - watch.slope);
          if (std::isfinite(watch.full_step_potential) && denom > 0) {
            start = std::clamp(-watch.slope / denom, 0.1, 0.5);
          }
          alpha = start;
          if (!LineSearch(x, watch.step, watch.slope, potential, residual_norm, load,
                          /*may_relax=*/false, &alpha, &relaxed, &trial)) {
            gradient = elastic_gradient;
            Extra(x, &gradient);
            residual = gradient - load;
            residual_norm = FreeNorm(residual);
            step_result = ForwardTermination::kLineSearchFailed;
            break;
          }
          Accept(&trial, &x, &elastic_gradient);
          elastic = trial.elastic;
          potential = trial.potential;
          gradient = elastic_gradient;
          Extra(x, &gradient);
          residual = gradient - load;
          residual_norm = FreeNorm(residual);
          step_length = alpha;
        }
      }
    }

    record.termination = step_result;
    record.final_residual_norm = residual_norm;
    summary_.load_steps.push_back(record);
  }

  // The last load step decides: an earlier one that stopped short only gave the next a
  // worse start (load steps are a continuation device), but the records and the message
  // keep it.
  const ForwardLoadStep& last = summary_.load_steps.back();
  summary_.termination = last.termination;
  std::ostringstream os;
  os << std::setprecision(4);
  const int steps = options_.load_steps;
  std::string earlier;
  for (const ForwardLoadStep& step : summary_.load_steps) {
    if (&step == &last || step.termination == ForwardTermination::kConverged) continue;
    earlier += (earlier.empty() ? "" : ", ") + std::to_string(step.load_step) + " (" +
               ToString(step.termination) + ")";
  }
  switch (last.termination) {
    case ForwardTermination::kConverged:
      os << "converged: |residual| " << residual_norm << " N <= " << tolerance
         << " N; Newton iterations per load step: " << IterationsPerStep(summary_.load_steps);
      if (!earlier.empty()) os << "; earlier load steps that did not converge: " << earlier;
      break;
    case ForwardTermination::kMaxIterations:
      os << "not converged: max_iterations (" << options_.max_iterations
         << ") reached at load step " << last.load_step << " of " << steps << " (load factor "
         << last.load_factor << "), |residual| " << residual_norm << " N > " << tolerance << " N";
      break;
    default:
      os << "not converged: the line search found no decrease of the potential above min_step ("
         << options_.min_step << ") at load step " << last.load_step << " of " << steps
         << " (load factor " << last.load_factor << "), |residual| " << residual_norm
         << " N > " << tolerance << " N";
      break;
  }
  if (last.termination != ForwardTermination::kConverged && last.load_step > 1) {
    if (earlier.empty()) {
      os << " (the earlier load steps converged)";
    } else {
      os << " (earlier load steps that did not converge: " << earlier << ")";
    }
  }
  if (last.termination != ForwardTermination::kConverged) {
    os << ". Try more load steps (forward.load_steps, now " << steps
       << ") or a larger forward.max_iterations; if it still fails, the load may have no "
          "equilibrium that the model can represent: look for inverted elements ("
       << "inverted_elements in the summary), e.g. a very soft material under its own weight";
  }
  summary_.message = os.str();

  mesh_.x = x;
  summary_.final_residual_norm = residual_norm;
  summary_.final_energy = potential;
  summary_.max_displacement = (x - mesh_.rest).rowwise().norm().maxCoeff();
  int inverted = 0;
  for (int e = 0; e < nt(); ++e) {
    const Vector12 xe = model_.Gather(x, e);
    Eigen::Matrix<double, 3, 4> xm;
    for (int k = 0; k < 4; ++k) xm.col(k) = xe.segment<3>(3 * k);
    if (!(DeformationGradient(xm, model_.rest(e).dm_inv).determinant() > 0)) ++inverted;
  }
  summary_.inverted_elements = inverted;
}

}  // namespace

Status SolveQuasiStatic(const ForwardProblem& problem, const ForwardOptions& options,
                        ElasticModel* model, TetMesh* mesh, ForwardSummary* summary) {
  const auto start = Clock::now();
  *summary = ForwardSummary();
  QuasiStaticSolver solver(problem, options, model, mesh, summary);
  {
    const ScopedThreads threads(summary->num_threads);
    if (solver.Validate() && solver.Setup()) solver.Run();
  }
  // Leave the model's rotations consistent with the result.
  if (summary->termination != ForwardTermination::kInvalidInput) model->UpdateRotations(mesh->x);
  summary->total_time_s = Seconds(start);
  if (summary->termination == ForwardTermination::kInvalidInput ||
      summary->termination == ForwardTermination::kFactorizationFailed) {
    return Status::Error(std::string("SolveQuasiStatic: ") + ToString(summary->termination) +
                         ": " + summary->message);
  }
  return Status::Ok();
}

Status EvaluateForwardSystem(const ForwardProblem& problem, const ForwardOptions& options,
                             const ElasticModel& model, const TetMesh& mesh, const Vertices& x,
                             Eigen::VectorXd* residual, Eigen::SparseMatrix<double>* tangent,
                             std::vector<int>* free_dofs) {
  if (x.rows() != mesh.num_vertices() || x.cols() != 3 || !x.allFinite()) {
    return Status::Error("EvaluateForwardSystem: x must be a finite #V by 3 matrix");
  }
  ForwardSummary summary;
  TetMesh copy = mesh;  // the solver's mesh is writable; this one is not written
  QuasiStaticSolver solver(problem, options, &model, &copy, &summary);
  const ScopedThreads threads(summary.num_threads);
  if (!solver.Validate() || !solver.Setup()) {
    return Status::Error(std::string("EvaluateForwardSystem: ") + ToString(summary.termination) +
                         ": " + summary.message);
  }
  solver.EvaluateSystem(x, options.tangent, residual, tangent, free_dofs);
  return Status::Ok();
}

}  // namespace femreg
