#include "solvers/fast/fast_backend.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <type_traits>
#include <utility>
#include <vector>

namespace femreg {
namespace fast_backend {

namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

template <class T>
using BlockType = typename std::decay_t<decltype(std::declval<T>().blocks())>::value_type;

// Where the 3x3 block (a, b) of the system sits in the values of a column-major matrix with
// full 3x3 blocks: entry (3a + i, 3b + j) is at offset + j * stride + i.
struct Slot {
  int offset = -1;
  int stride = 0;
};

}  // namespace

struct FastBackend::Impl {
  BackendOptions options;

  // The pattern: 3 #V by 3 #V, both triangles, full 3x3 blocks for the coupling's cells,
  // the diagonal and the extra pairs.
  int num_vertices = -1;
  uint64_t coupling_revision = 0;
  std::vector<std::pair<int, int>> extra_pairs;  // a < b
  Eigen::SparseMatrix<double> H;
  std::vector<int> diagonal_at;  // per column: where its diagonal entry sits
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> cholesky;
  bool analysed = false;

  // Per set revision, each block's slots (#blocks * n * n), found once per set.
  std::map<uint64_t, std::vector<Slot>> slots;
  std::map<uint64_t, bool> slots_used;

  // The part of H that is constant within one Solve.
  std::vector<double> constant_values;

  void ResetPattern(const energy::Problem& problem);
  void BuildPattern(const std::vector<std::array<int, 4>>& cells);
  Slot Find(int a, int b) const;
  // The slots of a set's blocks; pairs outside the pattern are added to *missing.
  template <class Set>
  const std::vector<Slot>& SlotsOf(const Set& set, std::vector<std::pair<int, int>>* missing);
  // Adds the blocks of the sets for which take(set) holds: gradient always, Hessian when
  // hessian(set).
  template <class Take, class WithHessian>
  void Accumulate(const energy::Problem& problem, const Vertices& x, Take take,
                  WithHessian hessian, Eigen::VectorXd* g);
  void Assemble(const energy::Problem& problem, const Vertices& x, bool first, Eigen::VectorXd* g);
  std::vector<std::array<int, 4>> cells;  // the coupling the pattern was built from
};

FastBackend::FastBackend(const BackendOptions& options) : impl_(new Impl) {
  impl_->options = options;
}
FastBackend::~FastBackend() = default;

void FastBackend::Impl::ResetPattern(const energy::Problem& problem) {
  num_vertices = problem.num_vertices();
  coupling_revision = problem.coupling_revision();
  cells = problem.coupling();
  extra_pairs.clear();
  BuildPattern(cells);
}

void FastBackend::Impl::BuildPattern(const std::vector<std::array<int, 4>>& cells) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(cells.size() * 144 + 9 * static_cast<size_t>(num_vertices) +
                   18 * extra_pairs.size());
  auto add = [&](int a, int b) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) triplets.emplace_back(3 * a + i, 3 * b + j, 0.0);
  };
  for (int v = 0; v < num_vertices; ++v) add(v, v);
  for (const auto& c : cells) {
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) add(c[a], c[b]);
  }
  for (const auto& p : extra_pairs) {
    add(p.first, p.second);
    add(p.second, p.first);
  }
  H.resize(3 * num_vertices, 3 * num_vertices);
  H.setFromTriplets(triplets.begin(), triplets.end());
  H.makeCompressed();
  const int n = static_cast<int>(H.cols());
  const int* outer = H.outerIndexPtr();
  const int* inner = H.innerIndexPtr();
  diagonal_at.assign(static_cast<size_t>(n), -1);
  for (int c = 0; c < n; ++c) {
    diagonal_at[static_cast<size_t>(c)] =
        static_cast<int>(std::lower_bound(inner + outer[c], inner + outer[c + 1], c) - inner);
  }
  analysed = false;
  slots.clear();
  slots_used.clear();
  constant_values.clear();
}

Slot FastBackend::Impl::Find(int a, int b) const {
  const int* outer = H.outerIndexPtr();
  const int* inner = H.innerIndexPtr();
  const int* begin = inner + outer[3 * b];
  const int* end = inner + outer[3 * b + 1];
  const int* p = std::lower_bound(begin, end, 3 * a);
  if (p == end || *p != 3 * a) return Slot();
  return Slot{static_cast<int>(p - inner), outer[3 * b + 1] - outer[3 * b]};
}

template <class Set>
const std::vector<Slot>& FastBackend::Impl::SlotsOf(const Set& set,
                                                   std::vector<std::pair<int, int>>* missing) {
  using T = BlockType<Set>;
  constexpr int n = T::kVertices;
  slots_used[set.revision()] = true;
  auto it = slots.find(set.revision());
  if (it != slots.end()) return it->second;
  std::vector<Slot>& s = slots[set.revision()];
  s.resize(static_cast<size_t>(set.size()) * n * n);
  size_t k = 0;
  for (const T& block : set.blocks()) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j, ++k) {
        s[k] = Find(block.vertices[i], block.vertices[j]);
        if (s[k].offset < 0) {
          missing->emplace_back(std::min(block.vertices[i], block.vertices[j]),
                                std::max(block.vertices[i], block.vertices[j]));
        }
      }
    }
  }
  return s;
}

template <class Take, class WithHessian>
void FastBackend::Impl::Accumulate(const energy::Problem& problem, const Vertices& x, Take take,
                                   WithHessian hessian, Eigen::VectorXd* g) {
  double* values = H.valuePtr();
  problem.ForEachSet([&](const auto& set) {
    if (!take(set)) return;
    using T = BlockType<std::decay_t<decltype(set)>>;
    constexpr int n = T::kVertices;
    const bool with_hessian = hessian(set);
    std::vector<std::pair<int, int>> missing;
    const std::vector<Slot>& s = SlotsOf(set, &missing);  // complete: checked before
    energy::Linearization<T> lin;
    size_t k = 0;
    for (const T& block : set.blocks()) {
      const size_t first = k;
      k += static_cast<size_t>(n) * n;
      if (!energy::Linearize(block, set.loss(), x, &lin, with_hessian) || lin.scale == 0.0) continue;
      for (int i = 0; i < n; ++i) g->segment<3>(3 * block.vertices[i]) += lin.gradient[i];
      if (!with_hessian) continue;
      for (int ij = 0; ij < n * n; ++ij) {
        const Slot& slot = s[first + ij];
        const Eigen::Matrix3d& M = lin.hessian[ij];
        for (int j = 0; j < 3; ++j) {
          double* column = values + slot.offset + j * slot.stride;
          for (int i = 0; i < 3; ++i) column[i] += M(i, j);
        }
      }
    }
  });
}

void FastBackend::Impl::Assemble(const energy::Problem& problem, const Vertices& x, bool first,
                                 Eigen::VectorXd* g) {
  auto constant = [](const auto& set) {
    using T = BlockType<std::decay_t<decltype(set)>>;
    return T::kConstantJacobian && !set.loss().robust();
  };
  auto varying = [&](const auto& set) { return !constant(set); };
  auto always = [](const auto&) { return true; };
  g->setZero(3 * num_vertices);
  if (first) {
    std::fill(H.valuePtr(), H.valuePtr() + H.nonZeros(), 0.0);
    Accumulate(problem, x, constant, always, g);
    constant_values.assign(H.valuePtr(), H.valuePtr() + H.nonZeros());
  } else {
    std::copy(constant_values.begin(), constant_values.end(), H.valuePtr());
    Accumulate(problem, x, constant, [](const auto&) { return false; }, g);
  }
  Accumulate(problem, x, varying, always, g);
}

SolveReport FastBackend::Solve(const energy::Problem& problem, double time_limit_s, Vertices* x) {
  const auto start = Clock::now();
  Impl& m = *impl_;
  SolveReport report;
  if (x->rows() != problem.num_vertices()) {
    report.message = "fast back end: the problem has " + std::to_string(problem.num_vertices()) +
                     " vertices, x has " + std::to_string(x->rows());
    return report;
  }
  if (m.num_vertices != problem.num_vertices() || m.coupling_revision != problem.coupling_revision()) {
    m.ResetPattern(problem);
    ++report.pattern_rebuilds;
  }
  // Every block's slots; pairs outside the pattern widen it (and redo the analysis).
  {
    for (auto& used : m.slots_used) used.second = false;
    std::vector<std::pair<int, int>> missing;
    problem.ForEachSet([&](const auto& set) { m.SlotsOf(set, &missing); });
    missing.erase(std::remove_if(missing.begin(), missing.end(),
                                 [](const std::pair<int, int>& p) { return p.first == p.second; }),
                  missing.end());
    if (!missing.empty()) {
      std::sort(missing.begin(), missing.end());
      missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
      m.extra_pairs.insert(m.extra_pairs.end(), missing.begin(), missing.end());
      m.BuildPattern(m.cells);
      ++report.pattern_rebuilds;
      problem.ForEachSet([&](const auto& set) { m.SlotsOf(set, &missing); });
    }
    // Forget the slots of sets that are gone.
    for (auto it = m.slots_used.begin(); it != m.slots_used.end();) {
      if (!it->second) {
        m.slots.erase(it->first);
        it = m.slots_used.erase(it);
      } else {
        ++it;
      }
    }
  }

  const int n = static_cast<int>(m.H.cols());
  const int* outer = m.H.outerIndexPtr();
  const int* inner = m.H.innerIndexPtr();
  const bool any_fixed = !problem.fixed().empty();
  double energy = problem.Evaluate(*x).total();
  double lambda = 1e-8;
  double first_gradient = -1.0;
  Eigen::VectorXd g;
  std::vector<double> diagonal(static_cast<size_t>(n));
  const int max_iterations = m.options.max_iterations;
  int steps = 0;
  bool first = true;
  report.success = true;
  report.message = "fast back end: converged";
  while (steps < max_iterations) {
    m.Assemble(problem, *x, first, &g);
    first = false;
    double* values = m.H.valuePtr();
    if (any_fixed) {  // identity rows and columns, no step
      for (int c = 0; c < n; ++c) {
        const bool col_fixed = problem.is_fixed(c / 3);
        for (int p = outer[c]; p < outer[c + 1]; ++p) {
          if (col_fixed || problem.is_fixed(inner[p] / 3)) values[p] = (inner[p] == c) ? 1.0 : 0.0;
        }
        if (col_fixed) g[c] = 0.0;
      }
    }
    // Converged when the gradient has fallen far below where it started: with rotations and
    // pairs fixed the problem is quadratic but for the robust weights, so this usually
    // holds right after the first step, without another factorization.
    const double gradient = g.lpNorm<Eigen::Infinity>();
    if (first_gradient < 0) first_gradient = gradient;
    if (gradient <= 1e-9 * first_gradient || gradient == 0.0) break;
    double max_diagonal = 0.0;
    for (int c = 0; c < n; ++c) {
      diagonal[static_cast<size_t>(c)] = values[m.diagonal_at[static_cast<size_t>(c)]];
      max_diagonal = std::max(max_diagonal, diagonal[static_cast<size_t>(c)]);
    }
    bool accepted = false;
    bool done = false;
    while (!accepted && steps < max_iterations) {
      // Marquardt damping on the diagonal (and a whisper of Tikhonov for unreferenced dofs).
      for (int c = 0; c < n; ++c) {
        values[m.diagonal_at[static_cast<size_t>(c)]] =
            diagonal[static_cast<size_t>(c)] * (1.0 + lambda) + 1e-12 * max_diagonal;
      }
      if (!m.analysed) {
        m.cholesky.analyzePattern(m.H);
        m.analysed = true;
      }
      m.cholesky.factorize(m.H);
      ++report.factorizations;
      ++steps;
      if (m.cholesky.info() != Eigen::Success) {
        lambda = std::max(lambda * 100.0, 1e-6);
        continue;
      }
      const Eigen::VectorXd dx = m.cholesky.solve(-g);
      ++report.linear_solves;
      Vertices trial = *x;
      for (int v = 0; v < m.num_vertices; ++v) trial.row(v) += dx.segment<3>(3 * v).transpose();
      const double trial_energy = problem.Evaluate(trial).total();
      if (std::isfinite(trial_energy) && trial_energy <= energy) {
        const double change = (energy - trial_energy) / std::max(energy, 1e-300);
        *x = trial;
        energy = trial_energy;
        lambda = std::max(lambda * 0.1, 1e-12);
        accepted = true;
        if (change < m.options.relative_tolerance || dx.lpNorm<Eigen::Infinity>() < 1e-14) done = true;
      } else {
        lambda = std::max(lambda * 10.0, 1e-6);
      }
      if (time_limit_s > 0 && Seconds(start) >= time_limit_s) done = true;
    }
    if (!accepted || done) break;
  }
  report.iterations = steps;
  if (!x->allFinite()) {
    report.success = false;
    report.message = "fast back end: the step made the positions non-finite";
  }
  return report;
}


}  // namespace fast_backend
}  // namespace femreg
