#include "solvers/fast/step_modes.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "mesh/disjoint_sets.h"

namespace femreg {
namespace fast_backend {

void StepModes::Build(const energy::Problem& problem, const Vertices& x, const Product& product) {
  HeldTurns(problem, x);
  FindFreePieces(problem);
  RigidModes(problem, x, product);
}

void StepModes::HeldTurns(const energy::Problem& problem, const Vertices& x) {
  held_.clear();
  held_range_.clear();
  if (problem.equilibrium() == nullptr) return;
  const int n = problem.num_vertices();
  for (const energy::Equilibrium::HeldTurn& turn : problem.equilibrium()->held_turns) {
    if (turn.count < 2) continue;
    bool fixed = false;  // a fixed vertex holds every turn already
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int v = turn.first; v < turn.first + turn.count; ++v) {
      fixed = fixed || problem.is_fixed(v);
      centre += x.row(v).transpose();
    }
    if (fixed) continue;
    centre /= static_cast<double>(turn.count);
    Eigen::VectorXd m = Eigen::VectorXd::Zero(3 * n);
    for (int v = turn.first; v < turn.first + turn.count; ++v) {
      m.segment<3>(3 * v) = turn.axis.cross(x.row(v).transpose() - centre);
    }
    const double before = m.norm();
    for (const Eigen::VectorXd& h : held_) m -= h.dot(m) * h;
    const double norm = m.norm();
    if (!(norm > 1e-8 * before)) continue;  // zero, or a turn the others hold already
    held_.push_back(m / norm);
    held_range_.emplace_back(turn.first, turn.first + turn.count);
  }
}

void StepModes::FindFreePieces(const energy::Problem& problem) {
  const int n = problem.num_vertices();
  DisjointSets sets(n);
  for (const auto& cell : problem.coupling()) {
    for (int k = 1; k < 4; ++k) sets.Unite(cell[0], cell[k]);
  }
  std::vector<int> piece_of(static_cast<size_t>(n), -1);
  std::vector<std::vector<int>> pieces;
  std::vector<char> fixed;
  for (int v = 0; v < n; ++v) {
    const int root = sets.Find(v);
    if (piece_of[static_cast<size_t>(root)] < 0) {
      piece_of[static_cast<size_t>(root)] = static_cast<int>(pieces.size());
      pieces.emplace_back();
      fixed.push_back(0);
    }
    const int p = piece_of[static_cast<size_t>(root)];
    pieces[static_cast<size_t>(p)].push_back(v);
    if (problem.is_fixed(v)) fixed[static_cast<size_t>(p)] = 1;
  }
  free_pieces_.clear();
  for (size_t p = 0; p < pieces.size(); ++p) {
    if (!fixed[p] && pieces[p].size() >= 2) free_pieces_.push_back(std::move(pieces[p]));
  }
}

void StepModes::RigidModes(const energy::Problem& problem, const Vertices& x, const Product& product) {
  modes_.clear();
  const int n = problem.num_vertices();
  // The modes of the pieces a held turn reaches: a held turn spans its object's pieces, so
  // their modes, made orthogonal to it, overlap one another's pieces.
  std::vector<size_t> reached;
  for (const std::vector<int>& piece : free_pieces_) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int v : piece) centre += x.row(v).transpose();
    centre /= static_cast<double>(piece.size());
    const size_t first = modes_.size();
    const bool reaches = std::any_of(held_range_.begin(), held_range_.end(), [&](const std::pair<int, int>& range) {
      const auto it = std::lower_bound(piece.begin(), piece.end(), range.first);  // pieces are sorted
      return it != piece.end() && *it < range.second;
    });
    for (int k = 0; k < 6; ++k) {
      Eigen::VectorXd m = Eigen::VectorXd::Zero(3 * n);
      for (int v : piece) {
        if (k < 3) {
          m[3 * v + k] = 1.0;
        } else {
          m.segment<3>(3 * v) = Eigen::Vector3d::Unit(k - 3).cross(x.row(v).transpose() - centre);
        }
      }
      if (reaches) {
        ProjectHeld(&m);
        for (size_t j : reached) m -= modes_[j].dot(m) * modes_[j];
      }
      for (size_t j = first; j < modes_.size(); ++j) m -= modes_[j].dot(m) * modes_[j];
      const double norm = m.norm();
      if (norm > 1e-12 * std::sqrt(static_cast<double>(piece.size()))) modes_.push_back(m / norm);
    }
    if (reaches) {
      for (size_t j = first; j < modes_.size(); ++j) reached.push_back(j);
    }
  }
  const int c = static_cast<int>(modes_.size());
  coarse_inverse_.resize(0, 0);
  if (c == 0) return;
  Eigen::MatrixXd coarse(c, c);
  Eigen::VectorXd am;
  for (int j = 0; j < c; ++j) {
    product(modes_[static_cast<size_t>(j)], &am);
    for (int i = 0; i < c; ++i) coarse(i, j) = modes_[static_cast<size_t>(i)].dot(am);
  }
  coarse = 0.5 * (coarse + coarse.transpose()).eval();
  Eigen::LDLT<Eigen::MatrixXd> ldlt(coarse);
  const double largest = coarse.diagonal().cwiseAbs().maxCoeff();
  if (ldlt.info() != Eigen::Success || !(largest > 0) || ldlt.vectorD().minCoeff() <= 1e-14 * largest) {
    // A rigid motion nothing resists (no data on the piece): the whisper of Tikhonov the
    // objective's assembly adds stands for it.
    coarse.diagonal().array() += 1e-12 * std::max(largest, 1.0);
    ldlt.compute(coarse);
  }
  coarse_inverse_ = ldlt.solve(Eigen::MatrixXd::Identity(c, c));
}

void StepModes::ProjectHeld(Eigen::VectorXd* v) const {
  for (const Eigen::VectorXd& h : held_) *v -= h.dot(*v) * h;
}

void StepModes::Project(Eigen::VectorXd* v) const {
  for (const Eigen::VectorXd& m : modes_) *v -= m.dot(*v) * m;
  ProjectHeld(v);
}

void StepModes::AddCoarse(const Eigen::VectorXd& r, Eigen::VectorXd* z) const {
  if (modes_.empty()) return;
  Eigen::VectorXd coefficients(static_cast<Eigen::Index>(modes_.size()));
  for (size_t j = 0; j < modes_.size(); ++j) coefficients[static_cast<Eigen::Index>(j)] = modes_[j].dot(r);
  const Eigen::VectorXd solved = coarse_inverse_ * coefficients;
  for (size_t j = 0; j < modes_.size(); ++j) *z += solved[static_cast<Eigen::Index>(j)] * modes_[j];
}

}  // namespace fast_backend
}  // namespace femreg
