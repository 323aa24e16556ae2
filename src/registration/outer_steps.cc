#include "registration/outer_steps.h"

#include <Eigen/QR>
#include <cmath>
#include <limits>

namespace femreg {

void OuterStepHistory::Record(int k, const Vertices& start, const Vertices& reached) {
  if (k != last_k_ + 1 || (!results_.empty() && results_.back().rows() != reached.rows())) Clear();
  last_k_ = k;
  results_.push_back(reached);
  moves_.push_back(reached - start);
  if (results_.size() > static_cast<size_t>(depth_) + 1) {
    results_.erase(results_.begin());
    moves_.erase(moves_.begin());
  }
}

bool OuterStepHistory::Propose(Vertices* further) const {
  const size_t n = moves_.size();
  if (n < 2) return false;
  const int m = static_cast<int>(n - 1);
  const Eigen::Index rows = moves_.back().rows(), size = moves_.back().size();
  Eigen::MatrixXd dF(size, m), dG(size, m);
  for (int j = 0; j < m; ++j) {
    const size_t a = n - 1 - static_cast<size_t>(j), b = a - 1;
    const Vertices df = moves_[a] - moves_[b], dg = results_[a] - results_[b];
    dF.col(j) = Eigen::Map<const Eigen::VectorXd>(df.data(), size);
    dG.col(j) = Eigen::Map<const Eigen::VectorXd>(dg.data(), size);
  }
  // Column pivoting: two differences along one line leave one column; none (a move that
  // repeats unchanged) leaves nothing to say where the iterations end.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(dF);
  if (qr.rank() == 0) return false;
  const Eigen::VectorXd gamma =
      qr.solve(Eigen::Map<const Eigen::VectorXd>(moves_.back().data(), size));
  const Eigen::VectorXd step = -(dG * gamma);
  if (!gamma.allFinite() || !step.allFinite()) return false;
  *further = results_.back() + Eigen::Map<const Vertices>(step.data(), rows, 3);
  return true;
}

OuterStepTrial TryOuterStep(const Vertices& reached, const Vertices& further,
                            const std::function<double(const Vertices&)>& energy) {
  OuterStepTrial trial;
  trial.further = std::numeric_limits<double>::infinity();
  trial.at = energy(reached);
  if (!std::isfinite(trial.at)) return trial;
  trial.further = energy(further);
  trial.kept = trial.further < trial.at;
  return trial;
}

}  // namespace femreg
