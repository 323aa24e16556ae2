// The forward solve's set-up and its linear algebra: inputs checked, DOFs numbered, the energy
// built on the energy layer, the reduced system filled and factorized.
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "forward/quasi_static_solver.h"
#include "parallel/signals.h"

namespace femreg {
namespace forward_internal {

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

bool QuasiStaticSolver::Setup(bool reduced) {
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
  if (free_dofs_.empty() || !reduced) return true;
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

void QuasiStaticSolver::EvaluateForces(const Vertices& x, ForwardForces* forces) {
  Eigen::VectorXd gradient;
  Elastic(x, &gradient);
  Eigen::VectorXd extra = Eigen::VectorXd::Zero(3 * nv());
  if (problem_.potential != nullptr) {
    problem_.potential->Refresh(x);
    Extra(x, &extra);
  }
  forces->reactions = Vertices::Zero(nv(), 3);
  forces->potential = -Eigen::Map<const Vertices>(extra.data(), nv(), 3);
  forces->loads = Eigen::Map<const Vertices>(full_load_.data(), nv(), 3);
  // A held vertex's row of the residual is what its support must supply.
  const Eigen::VectorXd residual = gradient + extra - full_load_;
  for (int v = 0; v < nv(); ++v) {
    if (free_index_[3 * v] < 0) forces->reactions.row(v) = residual.segment<3>(3 * v).transpose();
  }
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
  for (int e = 0; e < nt(); ++e) {
    // K's diagonal: V (mu |b_i|^2 + (lambda + mu) b_ia^2) for shape gradient b_i.
    const ElementRest& rest = model_.rest(e);
    const Eigen::Matrix<double, 3, 4> b = ShapeGradients(rest);
    for (int i = 0; i < 4; ++i) {
      const double diagonal = rest.mu * b.col(i).squaredNorm() + (rest.lambda + rest.mu) * b.col(i).cwiseAbs2().maxCoeff();
      max_diagonal = std::max(max_diagonal, rest.volume * diagonal);
    }
  }
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

}  // namespace forward_internal
}  // namespace femreg
