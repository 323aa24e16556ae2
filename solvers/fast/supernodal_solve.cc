#include "solvers/fast/supernodal_solve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <type_traits>

#include "parallel/threads.h"

// The supernodal solve's parts: the structure and the plan here (TakeStructure, the tree's
// cut, PrepareFactorization), the factorization in supernodal_factorize.cc, the
// substitutions in supernodal_substitute.cc.

namespace femreg {
namespace fast_backend {

namespace {


// Cuts the supernodal elimination tree for `threads` groups: subtrees grouped into one
// set per group (owner[s] = its group) and the rest, the top (owner -1), which runs after
// them: on one thread in the substitutions, and in the factorization its large supernodes
// in tiles on the whole team, the others on one thread. (The cost below still counts the
// top as serial, as it is for the substitutions the cut is made for.) Starting from the roots, the heaviest subtree is split (its root goes to the top,
// its children become subtrees) while that lowers the cost top + largest group; the groups
// are filled heaviest subtree first into the lightest group. Empty: no cut beats one thread.
std::vector<int> CutTree(const std::vector<int>& parent, const std::vector<double>& work,
                         int threads) {
  const int nsuper = static_cast<int>(parent.size());
  std::vector<double> subtree(work);
  std::vector<std::vector<int>> children(static_cast<size_t>(nsuper));
  std::vector<int> candidates;
  for (int s = 0; s < nsuper; ++s) {  // a parent comes after its children
    if (parent[s] >= 0) {
      subtree[static_cast<size_t>(parent[s])] += subtree[static_cast<size_t>(s)];
      children[static_cast<size_t>(parent[s])].push_back(s);
    } else {
      candidates.push_back(s);
    }
  }
  const double total = std::accumulate(work.begin(), work.end(), 0.0);
  std::vector<int> top, best_top, best_candidates;
  std::vector<int> best_bin_of;
  double top_work = 0.0, best_cost = total;  // everything on one thread
  auto by_weight = [&](int a, int b) {
    return subtree[static_cast<size_t>(a)] > subtree[static_cast<size_t>(b)] ||
           (subtree[static_cast<size_t>(a)] == subtree[static_cast<size_t>(b)] && a < b);
  };
  for (int round = 0; round < nsuper && !candidates.empty(); ++round) {
    std::sort(candidates.begin(), candidates.end(), by_weight);
    std::vector<double> bins(static_cast<size_t>(threads), 0.0);
    std::vector<int> bin_of(candidates.size());
    for (size_t k = 0; k < candidates.size(); ++k) {
      const size_t lightest = static_cast<size_t>(std::min_element(bins.begin(), bins.end()) - bins.begin());
      bins[lightest] += subtree[static_cast<size_t>(candidates[k])];
      bin_of[k] = static_cast<int>(lightest);
    }
    const double cost = top_work + *std::max_element(bins.begin(), bins.end());
    if (cost < best_cost) {
      best_cost = cost;
      best_top = top;
      best_candidates = candidates;
      best_bin_of = bin_of;
    }
    // Split the heaviest subtree, unless it is a leaf or already small, or the top alone
    // already costs as much as the best cut (it only grows).
    const int heaviest = candidates.front();
    if (children[static_cast<size_t>(heaviest)].empty() || top_work + work[static_cast<size_t>(heaviest)] >= best_cost ||
        subtree[static_cast<size_t>(heaviest)] < 0.25 * total / threads) {
      break;
    }
    candidates.erase(candidates.begin());
    top.push_back(heaviest);
    top_work += work[static_cast<size_t>(heaviest)];
    for (int c : children[static_cast<size_t>(heaviest)]) candidates.push_back(c);
  }
  if (best_candidates.empty()) return {};  // no cut does better than one thread
  std::vector<int> owner(static_cast<size_t>(nsuper), -2);
  for (int s : best_top) owner[static_cast<size_t>(s)] = -1;
  for (size_t k = 0; k < best_candidates.size(); ++k) {
    owner[static_cast<size_t>(best_candidates[k])] = best_bin_of[k];
  }
  for (int s = nsuper - 1; s >= 0; --s) {  // below a subtree's root: its owner
    if (owner[static_cast<size_t>(s)] == -2) owner[static_cast<size_t>(s)] = owner[static_cast<size_t>(parent[s])];
  }
  return owner;
}

}  // namespace

template <class Scalar>
bool SupernodalSolve<Scalar>::TakeStructure(const cholmod_factor& L) {
  // (CHOLMOD's supernodal factors are always LL^T; a symbolic one need not say so yet.)
  if (!L.is_super || L.itype != CHOLMOD_INT || L.super == nullptr || L.pi == nullptr ||
      L.px == nullptr || L.s == nullptr) {
    return false;
  }
  prepared_ = false;
  n_ = static_cast<int>(L.n);
  const int nsuper = static_cast<int>(L.nsuper);
  const int* super = static_cast<const int*>(L.super);
  const int* pi = static_cast<const int*>(L.pi);
  const int* px = static_cast<const int*>(L.px);
  const int* s = static_cast<const int*>(L.s);
  const int* perm = static_cast<const int*>(L.Perm);
  super_.assign(super, super + nsuper + 1);
  pi_.assign(pi, pi + nsuper + 1);
  px_.assign(px, px + nsuper + 1);
  rows_.assign(s, s + L.ssize);
  if (perm != nullptr) {
    perm_.assign(perm, perm + n_);
  } else {
    perm_.resize(static_cast<size_t>(n_));
    std::iota(perm_.begin(), perm_.end(), 0);
  }
  // The supernodal tree: a supernode's parent holds the first row below its diagonal
  // block. Work: the supernode's entries.
  super_of_.assign(static_cast<size_t>(n_), 0);
  for (int k = 0; k < nsuper; ++k) {
    for (int c = super[k]; c < super[k + 1]; ++c) super_of_[static_cast<size_t>(c)] = k;
  }
  std::vector<int> parent(static_cast<size_t>(nsuper), -1);
  std::vector<double> work(static_cast<size_t>(nsuper));
  double total = 0.0;
  for (int k = 0; k < nsuper; ++k) {
    const int ncol = super[k + 1] - super[k], nrow = pi[k + 1] - pi[k];
    if (nrow > ncol) parent[static_cast<size_t>(k)] = super_of_[static_cast<size_t>(s[pi[k] + ncol])];
    work[static_cast<size_t>(k)] = static_cast<double>(nrow) * ncol - 0.5 * ncol * (ncol - 1);
    total += work[static_cast<size_t>(k)];
  }
  groups_.assign(1, {});
  top_.clear();
  serial_fraction_ = 0.0;
  // The cut depends on L alone, never on the thread count: the same sums in the same order on
  // any number of threads (docs/notes/2026-11-29-threads.md).
  const std::vector<int> owner =
      total < static_cast<double>(cut_from_) ? std::vector<int>() : CutTree(parent, work, kGroups);
  if (owner.empty()) {  // too small to share, or no cut worth a team: the serial order
    groups_[0].resize(static_cast<size_t>(nsuper));
    std::iota(groups_[0].begin(), groups_[0].end(), 0);
    serial_fraction_ = 1.0;
  } else {
    groups_.assign(static_cast<size_t>(kGroups), {});
    for (int k = 0; k < nsuper; ++k) {
      const int o = owner[static_cast<size_t>(k)];
      if (o < 0) {
        top_.push_back(k);
        serial_fraction_ += work[static_cast<size_t>(k)] / std::max(total, 1.0);
      } else {
        groups_[static_cast<size_t>(o)].push_back(k);
      }
    }
  }
  max_rows_ = 0;
  for (int k = 0; k < nsuper; ++k) max_rows_ = std::max(max_rows_, pi[k + 1] - pi[k]);
  work_.Size(groups_.size(), n_, max_rows_);
  single_ = Workspace<Scalar>();
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::Load(const cholmod_factor& L, bool new_structure, int threads) {
  if (!L.is_super || !L.is_ll || L.itype != CHOLMOD_INT || L.xtype != CHOLMOD_REAL ||
      L.dtype != CHOLMOD_DOUBLE || L.x == nullptr || L.minor != L.n) {
    loaded_ = false;
    return false;
  }
  threads_ = std::max(1, threads);
  sign_.clear();
  negative_pivots_ = perturbed_pivots_ = 0;
  if (new_structure || !loaded_ || n_ != static_cast<int>(L.n) || super_.size() != L.nsuper + 1 ||
      values_.size() != L.xsize) {
    loaded_ = false;  // until the structure is whole again
    if (!TakeStructure(L)) return false;
  }
  const double* x = static_cast<const double*>(L.x);
  values_.resize(L.xsize);
  for (size_t k = 0; k < L.xsize; ++k) values_[k] = static_cast<Scalar>(x[k]);
  loaded_ = true;
  return true;
}

template <class Scalar>
bool SupernodalSolve<Scalar>::PrepareFactorization(const Eigen::SparseMatrix<double>& A) {
  prepared_ = false;
  if (A.rows() != n_ || A.cols() != n_ || !A.isCompressed()) return false;
  const int nsuper = static_cast<int>(super_.size()) - 1;
  // The updates: descendant d updates, with its rows [r1, r2) (below its diagonal block),
  // the supernode that holds row r1 and with the rows [r1, end) the entries below. Listed
  // by target, in ascending d.
  std::vector<std::vector<std::array<int, 3>>> by_target(static_cast<size_t>(nsuper));
  max_update_ = 0;
  max_signed_ = 0;
  for (int d = 0; d < nsuper; ++d) {
    const int ncol = super_[d + 1] - super_[d];
    const int nrow = pi_[d + 1] - pi_[d];
    max_signed_ = std::max<int64_t>(max_signed_, static_cast<int64_t>(ncol) * std::min(ncol, kIndefinitePanel));
    const int* rows = rows_.data() + pi_[d];
    int r = ncol;
    while (r < nrow) {
      const int t = super_of_[static_cast<size_t>(rows[r])];
      if (t <= d) return false;  // not a supernodal structure
      int r2 = r;
      while (r2 < nrow && rows[r2] < super_[t + 1]) ++r2;
      by_target[static_cast<size_t>(t)].push_back({d, r, r2});
      max_update_ = std::max<int64_t>(max_update_, static_cast<int64_t>(nrow - r) * (r2 - r));
      max_signed_ = std::max<int64_t>(max_signed_, static_cast<int64_t>(nrow - r) * ncol);
      r = r2;
    }
  }
  update_start_.assign(1, 0);
  update_d_.clear();
  update_r1_.clear();
  update_r2_.clear();
  for (int t = 0; t < nsuper; ++t) {
    for (const auto& u : by_target[static_cast<size_t>(t)]) {
      update_d_.push_back(u[0]);
      update_r1_.push_back(u[1]);
      update_r2_.push_back(u[2]);
    }
    update_start_.push_back(static_cast<int>(update_d_.size()));
  }
  // A's entries on or below the permuted diagonal, by supernode, and where each goes.
  std::vector<int> inverse(static_cast<size_t>(n_));
  for (int k = 0; k < n_; ++k) inverse[static_cast<size_t>(perm_[static_cast<size_t>(k)])] = k;
  std::vector<int> position(static_cast<size_t>(n_), -1);
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  a_start_.assign(1, 0);
  a_src_.clear();
  a_dst_.clear();
  for (int k = 0; k < nsuper; ++k) {
    const int k1 = super_[k], ncol = super_[k + 1] - k1, nrow = pi_[k + 1] - pi_[k];
    const int* rows = rows_.data() + pi_[k];
    for (int i = 0; i < nrow; ++i) position[static_cast<size_t>(rows[i])] = i;
    for (int j = 0; j < ncol; ++j) {
      const int column = perm_[static_cast<size_t>(k1 + j)];
      for (int p = outer[column]; p < outer[column + 1]; ++p) {
        const int row = inverse[static_cast<size_t>(inner[p])];
        if (row < k1 + j) continue;  // the upper triangle
        const int i = position[static_cast<size_t>(row)];
        if (i < 0 || rows[i] != row) return false;  // not in L's pattern: another matrix
        a_src_.push_back(p);
        a_dst_.push_back(px_[k] + static_cast<int64_t>(j) * nrow + i);
      }
    }
    for (int i = 0; i < nrow; ++i) position[static_cast<size_t>(rows[i])] = -1;
    a_start_.push_back(static_cast<int64_t>(a_src_.size()));
  }
  map_.assign(groups_.size(), std::vector<int>(static_cast<size_t>(n_), 0));
  c_.assign(groups_.size(), std::vector<Scalar>(static_cast<size_t>(max_update_)));
  signed_.assign(groups_.size(), {});
  prepared_outer_.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.cols() + 1);
  prepared_inner_.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  prepared_ = true;
  return true;
}

template class SupernodalSolve<float>;
template class SupernodalSolve<double>;

}  // namespace fast_backend
}  // namespace femreg
