#include "energy/assembler.h"

#include <algorithm>
#include <cstdint>
#include <type_traits>

#include "energy/nodal_volume.h"
#include "geometry/morton.h"
#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {
namespace energy {

namespace {

template <class T>
using BlockType = typename std::decay_t<decltype(std::declval<T>().blocks())>::value_type;

// A set is assembled on several threads once its blocks hold this many 3x3 Hessian blocks
// (#blocks x n^2): below, the team costs more than it saves, mostly the cache lines of H
// that the other core must fetch; a 1,543-vertex cage's sets (up to 118k) were faster serial
// (docs/notes/2026-11-30-two-threads.md).
constexpr int kParallelWork = 131072;
// The exact second-order linearization costs several times the Gauss-Newton one per block (a
// corotational element's rotation derivative, a neo-Hookean element's full Hessian), so its
// sets go to the team from this fraction of kParallelWork.
constexpr int kSecondOrderWorkFactor = 8;
// Fills and copies of H's values, passes over the whole matrix that wait on memory, go to the
// team from this many entries per thread on (about 8k vertices): on a smaller mesh the sets
// that follow are assembled serially and would fetch the half the other core wrote.
constexpr int64_t kParallelCopy = int64_t{1} << 19;
// Finish's passes over the diagonal, scattered over H: from this many entries per thread on.
constexpr int64_t kParallelDiagonal = int64_t{1} << 14;

// to[0, n) = from[0, n) (from == nullptr: zeros), in spans on up to `threads` threads (entry
// by entry: the same on any thread count).
void CopyValues(int threads, const double* from, int64_t n, double* to) {
  ParallelSpans(threads, n, kParallelCopy, [from, to](int64_t begin, int64_t end) {
    if (from == nullptr) {
      std::fill(to + begin, to + end, 0.0);
    } else {
      std::copy(from + begin, from + end, to + begin);
    }
  });
}

}  // namespace

void Assembler::ResetPattern(const Problem& problem, const Vertices& x) {
  num_vertices_ = problem.num_vertices();
  coupling_revision_ = problem.coupling_revision();
  cells_ = problem.coupling();
  extra_pairs_.clear();
  OrderVertices(x);
  BuildPattern();
}

void Assembler::OrderVertices(const Vertices& x) {
  const int n = num_vertices_;
  const std::vector<int> along = MortonOrder(x.topRows(n));
  owner_threads_ = threads_;
  vertex_owner_.assign(static_cast<size_t>(n), 0);
  for (int k = 0; k < n; ++k) {
    vertex_owner_[static_cast<size_t>(along[static_cast<size_t>(k)])] =
        static_cast<int>(static_cast<int64_t>(k) * threads_ / n);
  }
}

void Assembler::BuildPattern() {
  // Each vertex's neighbours (itself, its cells' vertices, its extra pairs), sorted; then the
  // compressed columns directly (column 3 b + j holds rows 3 a + i for every neighbour a of
  // b): several times faster than through 144 triplets per cell.
  std::vector<std::vector<int>> neighbours(static_cast<size_t>(num_vertices_));
  for (int v = 0; v < num_vertices_; ++v) neighbours[static_cast<size_t>(v)].push_back(v);
  for (const auto& c : cells_) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        if (a != b) neighbours[static_cast<size_t>(c[a])].push_back(c[b]);
      }
    }
  }
  for (const auto& p : extra_pairs_) {
    neighbours[static_cast<size_t>(p.first)].push_back(p.second);
    neighbours[static_cast<size_t>(p.second)].push_back(p.first);
  }
  int64_t nnz = 0;
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    nnz += 9 * static_cast<int64_t>(list.size());
  }
  H_ = Eigen::SparseMatrix<double>(3 * num_vertices_, 3 * num_vertices_);
  H_.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer_out = H_.outerIndexPtr();
  int* inner_out = H_.innerIndexPtr();
  int at = 0;
  for (int b = 0; b < num_vertices_; ++b) {
    for (int j = 0; j < 3; ++j) {
      outer_out[3 * b + j] = at;
      for (int a : neighbours[static_cast<size_t>(b)]) {
        for (int i = 0; i < 3; ++i) inner_out[at++] = 3 * a + i;
      }
    }
  }
  outer_out[3 * num_vertices_] = at;
  std::fill(H_.valuePtr(), H_.valuePtr() + nnz, 0.0);
  const int n = static_cast<int>(H_.cols());
  const int* outer = H_.outerIndexPtr();
  const int* inner = H_.innerIndexPtr();
  diagonal_at_.assign(static_cast<size_t>(n), -1);
  for (int c = 0; c < n; ++c) {
    diagonal_at_[static_cast<size_t>(c)] =
        static_cast<int>(std::lower_bound(inner + outer[c], inner + outer[c + 1], c) - inner);
  }
  block_rows_ = BlockRowVertices(H_);
  pattern_revision_ = NextRevision();
  cache_.clear();
  stencil_slots_.clear();
  stencil_pool_.clear();
  constant_values_.clear();
  fixed_for_.clear();
}

Assembler::Slot Assembler::Find(int a, int b) const {
  const int* outer = H_.outerIndexPtr();
  const int* inner = H_.innerIndexPtr();
  const int* begin = inner + outer[3 * b];
  const int* end = inner + outer[3 * b + 1];
  const int* p = std::lower_bound(begin, end, 3 * a);
  if (p == end || *p != 3 * a) return Slot();
  return Slot{static_cast<int>(p - inner), outer[3 * b + 1] - outer[3 * b]};
}

namespace {
// A key for a stencil of 2 or 3 vertices in that order, each below 2^20 - 1, or of 4 vertices
// each below 2^15 - 1 (an element: a cage's embedded-surface pairs, new every outer
// iteration, sit on its elements); 0 (no key) else.
template <size_t n>
uint64_t StencilKey(const std::array<int, n>& v) {
  static_assert(n >= 1);
  if constexpr (n == 4) {
    uint64_t key = 0;  // low bits 0: no 2- or 3-vertex key's
    for (size_t i = 0; i < n; ++i) {
      if (v[i] < 0 || v[i] + 1 >= (1 << 15)) return 0;
      key |= static_cast<uint64_t>(v[i] + 1) << (2 + 15 * i);
    }
    return key;
  } else if constexpr (n < 2 || n > 3) {
    return 0;
  } else {
    uint64_t key = n;  // the count in the low bits: (a, b) and (a, b, 0) differ
    for (size_t i = 0; i < n; ++i) {
      if (v[i] < 0 || v[i] + 1 >= (1 << 20)) return 0;
      key |= static_cast<uint64_t>(v[i] + 1) << (2 + 20 * i);
    }
    return key;
  }
}
}  // namespace

template <class Set>
Assembler::SetCache& Assembler::CacheOf(const Set& set,
                                                       std::vector<std::pair<int, int>>* missing) {
  using T = BlockType<Set>;
  constexpr int n = T::kVertices;
  auto it = cache_.find(set.revision());
  if (it != cache_.end()) {
    it->second.used = true;
    return it->second;
  }
  SetCache& c = cache_[set.revision()];
  c.used = true;
  c.slots.resize(static_cast<size_t>(set.size()) * n * n);
  size_t k = 0;
  for (const T& block : set.blocks()) {
    if constexpr (n == 1) {  // a vertex's diagonal block: where its first column's diagonal is
      const int v = block.vertices[0];
      if (v >= 0 && v < num_vertices_) {
        c.slots[k++] = Slot{diagonal_at_[static_cast<size_t>(3 * v)],
                            H_.outerIndexPtr()[3 * v + 1] - H_.outerIndexPtr()[3 * v]};
        continue;
      }
    }
    const uint64_t key = StencilKey(block.vertices);
    if (key != 0) {
      const auto known = stencil_slots_.find(key);
      if (known != stencil_slots_.end()) {
        std::copy_n(stencil_pool_.begin() + known->second, n * n, c.slots.begin() + static_cast<std::ptrdiff_t>(k));
        k += n * n;
        continue;
      }
    }
    bool complete = true;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        c.slots[k + static_cast<size_t>(i * n + j)] = Find(block.vertices[i], block.vertices[j]);
        if (c.slots[k + static_cast<size_t>(i * n + j)].offset < 0) {
          complete = false;
          missing->emplace_back(std::min(block.vertices[i], block.vertices[j]),
                                std::max(block.vertices[i], block.vertices[j]));
        }
      }
    }
    if (key != 0 && complete) {
      stencil_slots_.emplace(key, static_cast<int>(stencil_pool_.size()));
      stencil_pool_.insert(stencil_pool_.end(), c.slots.begin() + static_cast<std::ptrdiff_t>(k),
                          c.slots.begin() + static_cast<std::ptrdiff_t>(k + n * n));
    }
    k += n * n;
  }
  return c;
}

template <class Take, class WithHessian, class Linearizer>
void Assembler::Accumulate(const Problem& problem, const Vertices& x, Take take, WithHessian hessian,
                           Linearizer linearize, Eigen::VectorXd* g, std::vector<double>* set_energy,
                           int64_t parallel_work) {
  double* values = H_.valuePtr();
  double* gradient = g->data();
  int ordinal = -1;
  problem.ForEachSet([&](const auto& set) {
    ++ordinal;
    if (!((groups_ >> static_cast<int>(set.group())) & 1u) || !take(set)) return;
    using T = BlockType<std::decay_t<decltype(set)>>;
    constexpr int n = T::kVertices;
    const bool with_hessian = hessian(set);
    std::vector<std::pair<int, int>> missing;
    SetCache& c = CacheOf(set, &missing);  // complete: checked before
    const std::vector<T>& blocks = set.blocks();
    const int size = set.size();
    // Adds block b's linearization to the entries of H_ and g of the vertices that thread
    // `owner` owns (-1: all of them).
    const int* vertex_owner_of = vertex_owner_.data();
    auto scatter = [&](int b, const Eigen::Vector3d* grad, const Eigen::Matrix3d* hess, int owner) {
      const T& block = blocks[static_cast<size_t>(b)];
      for (int i = 0; i < n; ++i) {
        const int v = block.vertices[i];
        if (owner >= 0 && vertex_owner_of[v] != owner) continue;
        double* gi = gradient + 3 * v;
        for (int d = 0; d < 3; ++d) gi[d] += grad[i][d];
      }
      if (!with_hessian) return;
      const Slot* s = c.slots.data() + static_cast<size_t>(b) * n * n;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          const int column_vertex = block.vertices[j];
          if (owner >= 0 && vertex_owner_of[column_vertex] != owner) continue;
          const int ij = i * n + j;
          const Eigen::Matrix3d& M = hess[ij];
          for (int jj = 0; jj < 3; ++jj) {
            double* column = values + s[ij].offset + jj * s[ij].stride;
            for (int ii = 0; ii < 3; ++ii) column[ii] += M(ii, jj);
          }
        }
      }
    };
    // Each block's value (Linearize's: 0 where it cannot be evaluated), for set_energy.
    double* value_of = nullptr;
    if (set_energy != nullptr) {
      block_values_.resize(static_cast<size_t>(size));
      value_of = block_values_.data();
    }
    auto set_done = [&] {
      if (set_energy == nullptr) return;
      if (static_cast<int>(set_energy->size()) <= ordinal) set_energy->resize(static_cast<size_t>(ordinal) + 1, 0.0);
      (*set_energy)[static_cast<size_t>(ordinal)] = Problem::SumBlockValues(block_values_);
    };
    if (threads_ == 1 || static_cast<int64_t>(size) * n * n < parallel_work) {
      // One pass, no OpenMP region (even a team of one costs libgomp a futex wake-up).
      Linearization<T> lin;
      for (int b = 0; b < size; ++b) {
        const bool linearized = linearize(blocks[static_cast<size_t>(b)], set.loss(), &lin, with_hessian);
        if (value_of != nullptr) value_of[b] = lin.value;
        if (linearized && lin.scale != 0.0) scatter(b, lin.gradient.data(), lin.hessian.data(), -1);
      }
      set_done();
      return;
    }
    // A region of vertices per thread (vertex_owner_): a thread linearizes and adds its
    // interior blocks in one pass; the straddling ones are linearized in parallel into a
    // buffer and each thread adds their parts that land in its region.
    if (static_cast<int>(c.interior.size()) != threads_) {
      c.interior.assign(static_cast<size_t>(threads_), {});
      c.straddling.clear();
      for (int b = 0; b < size; ++b) {
        const T& block = blocks[static_cast<size_t>(b)];
        const int t = vertex_owner_[static_cast<size_t>(block.vertices[0])];
        bool interior = true;
        for (int i = 1; i < n; ++i) interior = interior && vertex_owner_[static_cast<size_t>(block.vertices[i])] == t;
        if (interior) {
          c.interior[static_cast<size_t>(t)].push_back(b);
        } else {
          // Its place among the thread's blocks (ascending b): ~k for the k-th straddling one.
          const int k = static_cast<int>(c.straddling.size());
          c.straddling.push_back(b);
          for (int i = 0; i < n; ++i) {
            std::vector<int>& walk = c.interior[static_cast<size_t>(vertex_owner_[static_cast<size_t>(block.vertices[i])])];
            if (walk.empty() || walk.back() != ~k) walk.push_back(~k);
          }
        }
      }
    }
    const std::vector<int>& straddling = c.straddling;
    const int num_straddling = static_cast<int>(straddling.size());
    // Per straddling block: a flag (1: adds something), n gradient vectors, n * n blocks.
    constexpr size_t kStride = 1 + 3 * n + 9 * n * n;
    // Grown, never shrunk: a shrink and a regrowth (the sets take turns) would zero the
    // regrown part every time.
    if (scratch_.size() < kStride * straddling.size()) scratch_.resize(kStride * straddling.size());
    double* buffer = scratch_.data();
    // Two steps on femreg's workers (parallel/pool.h): the straddling blocks in pieces, then
    // one task per region; the caller takes over a worker's part if it starts late.
    ParallelRanges(threads_, num_straddling, (num_straddling + 4 * threads_ - 1) / (4 * threads_),
                   [&](int64_t begin, int64_t end) {
      Linearization<T> lin;
      for (int64_t k = begin; k < end; ++k) {
        double* out = buffer + kStride * static_cast<size_t>(k);
        const int b = straddling[static_cast<size_t>(k)];
        const bool adds = linearize(blocks[static_cast<size_t>(b)], set.loss(), &lin, with_hessian) &&
                          lin.scale != 0.0;
        if (value_of != nullptr) value_of[b] = lin.value;
        out[0] = adds ? 1.0 : 0.0;
        if (!adds) continue;
        for (int i = 0; i < n; ++i) Eigen::Map<Eigen::Vector3d>(out + 1 + 3 * i) = lin.gradient[i];
        if (with_hessian) {
          for (int ij = 0; ij < n * n; ++ij) {
            Eigen::Map<Eigen::Matrix3d>(out + 1 + 3 * n + 9 * ij) = lin.hessian[ij];
          }
        }
      }
    });  // every straddling block is linearized
    RunTasks(threads_, threads_, [&](int t) {
      Linearization<T> lin;
      // The region's blocks in ascending order, interior and straddling alike: every entry
      // receives its terms in block order, as on one thread (docs/notes/2026-11-29-threads.md).
      for (int e : c.interior[static_cast<size_t>(t)]) {
        if (e >= 0) {
          const bool linearized = linearize(blocks[static_cast<size_t>(e)], set.loss(), &lin, with_hessian);
          if (value_of != nullptr) value_of[e] = lin.value;
          if (linearized && lin.scale != 0.0) scatter(e, lin.gradient.data(), lin.hessian.data(), -1);
          continue;
        }
        const int k = ~e;
        const double* in = buffer + kStride * static_cast<size_t>(k);
        if (in[0] == 0.0) continue;
        const int b = straddling[static_cast<size_t>(k)];
        for (int i = 0; i < n; ++i) lin.gradient[i] = Eigen::Map<const Eigen::Vector3d>(in + 1 + 3 * i);
        if (with_hessian) {
          for (int ij = 0; ij < n * n; ++ij) {
            lin.hessian[ij] = Eigen::Map<const Eigen::Matrix3d>(in + 1 + 3 * n + 9 * ij);
          }
        }
        scatter(b, lin.gradient.data(), lin.hessian.data(), t);
      }
    });
    set_done();
  });
}

int Assembler::Prepare(const Problem& problem, const Vertices& x,
                       const std::vector<std::pair<int, int>>& pairs) {
  int builds = 0;
  if (num_vertices_ != problem.num_vertices() || coupling_revision_ != problem.coupling_revision()) {
    ResetPattern(problem, x);
    ++builds;
  } else if (owner_threads_ != threads_) {
    OrderVertices(x);
    for (auto& c : cache_) c.second.interior.clear();
  }
  // Every block's slots; pairs outside the pattern widen it.
  for (auto& c : cache_) c.second.used = false;
  std::vector<std::pair<int, int>> missing;
  problem.ForEachSet([&](const auto& set) { CacheOf(set, &missing); });
  auto widen = [&](const std::vector<std::pair<int, int>>& list) {
    for (const auto& p : list) {
      if (p.first != p.second && Find(p.first, p.second).offset < 0) {
        missing.emplace_back(std::min(p.first, p.second), std::max(p.first, p.second));
      }
    }
  };
  widen(pairs);
  if (problem.nodal_volume() != nullptr) widen(problem.nodal_volume()->Pairs());
  missing.erase(std::remove_if(missing.begin(), missing.end(),
                               [](const std::pair<int, int>& p) { return p.first == p.second; }),
                missing.end());
  if (!missing.empty()) {
    std::sort(missing.begin(), missing.end());
    missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
    extra_pairs_.insert(extra_pairs_.end(), missing.begin(), missing.end());
    BuildPattern();
    ++builds;
    problem.ForEachSet([&](const auto& set) { CacheOf(set, &missing); });
  }
  for (auto it = cache_.begin(); it != cache_.end();) {  // forget the sets that are gone
    it = it->second.used ? std::next(it) : cache_.erase(it);
  }
  return builds;
}

EnergyTerms Assembler::SumByGroup(const Problem& problem, const std::vector<double>& set_energy) const {
  EnergyTerms terms;
  size_t ordinal = 0;
  problem.ForEachSet([&](const auto& set) {
    GroupEnergy(set.group(), &terms) += ordinal < set_energy.size() ? set_energy[ordinal] : 0.0;
    ++ordinal;
  });
  return terms;
}

void Assembler::AssembleGaussNewton(const Problem& problem, const Vertices& x, bool first,
                                    Eigen::VectorXd* g, EnergyTerms* energy) {
  auto constant = [](const auto& set) {
    using T = BlockType<std::decay_t<decltype(set)>>;
    return T::kConstantJacobian && !set.loss().robust();
  };
  auto varying = [&](const auto& set) { return !constant(set); };
  auto always = [](const auto&) { return true; };
  auto gauss_newton = [&x](const auto& block, const Loss& loss, auto* out, bool with_hessian) {
    using T = std::decay_t<decltype(block)>;
    if constexpr (HasNewtonCurvature<T>::value) {
      return LinearizeSecondOrder(block, loss, x, Curvature::kProjected, out, with_hessian);
    } else {
      return Linearize(block, loss, x, out, with_hessian);
    }
  };
  g->setZero(3 * num_vertices_);
  std::vector<double>* set_energy = first && energy != nullptr ? &set_energy_ : nullptr;
  if (set_energy != nullptr) set_energy->clear();
  const int64_t nnz = H_.nonZeros();
  if (first) {
    CopyValues(threads_, nullptr, nnz, H_.valuePtr());
    Accumulate(problem, x, constant, always, gauss_newton, g, set_energy, kParallelWork);
    constant_values_.resize(static_cast<size_t>(nnz));
    CopyValues(threads_, H_.valuePtr(), nnz, constant_values_.data());
  } else {
    // The constant sets' gradient is linearized element by element again, not formed as the
    // first one plus H_c (x - x_first): that sum cancels on nearly flat elements (a 1:1000
    // plate's stiffness against its small gradient; tests/hard_cases_test.cc).
    const int64_t kept = static_cast<int64_t>(constant_values_.size());
    CopyValues(threads_, constant_values_.data(), kept, H_.valuePtr());
    Accumulate(problem, x, constant, [](const auto&) { return false; }, gauss_newton, g, nullptr, kParallelWork);
  }
  Accumulate(problem, x, varying, always, gauss_newton, g, set_energy, kParallelWork);
  if (set_energy != nullptr) *energy = SumByGroup(problem, *set_energy);
  const double nodal = AddNodalVolume(problem, x, Curvature::kGaussNewton, true, g);
  if (set_energy != nullptr) energy->elastic += nodal;
  Finish(problem, 1e-12, g);
}

double Assembler::AssembleSecondOrder(const Problem& problem, const Vertices& x, Curvature curvature,
                                      bool with_hessian, Eigen::VectorXd* g) {
  auto always = [](const auto&) { return true; };
  auto hessian = [with_hessian](const auto&) { return with_hessian; };
  auto second_order = [&x, curvature](const auto& block, const Loss& loss, auto* out, bool with) {
    return LinearizeSecondOrder(block, loss, x, curvature, out, with);
  };
  g->setZero(3 * num_vertices_);
  if (with_hessian) CopyValues(threads_, nullptr, H_.nonZeros(), H_.valuePtr());
  set_energy_.clear();
  Accumulate(problem, x, always, hessian, second_order, g, &set_energy_, kParallelWork / kSecondOrderWorkFactor);
  const double nodal = AddNodalVolume(problem, x, curvature, with_hessian, g);
  return SumByGroup(problem, set_energy_).total() + nodal;
}

double Assembler::AddNodalVolume(const Problem& problem, const Vertices& x, Curvature curvature,
                                 bool with_hessian, Eigen::VectorXd* g) {
  const NodalVolume* nodal = problem.nodal_volume();
  if (nodal == nullptr || !InGroups(groups_, TermGroup::kElastic)) return 0.0;
  const double energy = nodal->Evaluate(x, g);
  if (with_hessian) nodal->AddHessian(x, curvature, this);
  return energy;
}

bool Assembler::AddBlock(int a, int b, const Eigen::Matrix3d& M) {
  if (Find(a, b).offset < 0) return false;  // not in the pattern: nothing written
  auto add = [this](int row, int column, const Eigen::Matrix3d& block) {
    const Slot s = Find(row, column);
    double* values = H_.valuePtr();
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) values[s.offset + j * s.stride + i] += block(i, j);
  };
  add(a, b, M);
  if (a != b) add(b, a, M.transpose());
  return true;
}

void Assembler::Finish(const Problem& problem, double whisper, Eigen::VectorXd* g) {
  // Hard anchors: identity rows and columns, no gradient.
  if (!problem.fixed().empty()) {
    if (fixed_for_ != problem.fixed()) {
      fixed_for_ = problem.fixed();
      fixed_off_diagonal_.clear();
      fixed_diagonal_.clear();
      const int n = static_cast<int>(H_.cols());
      const int* outer = H_.outerIndexPtr();
      const int* inner = H_.innerIndexPtr();
      for (int c = 0; c < n; ++c) {
        const bool col_fixed = problem.is_fixed(c / 3);
        for (int p = outer[c]; p < outer[c + 1]; ++p) {
          if (col_fixed || problem.is_fixed(inner[p] / 3)) {
            (inner[p] == c ? fixed_diagonal_ : fixed_off_diagonal_).push_back(p);
          }
        }
      }
    }
    double* values = H_.valuePtr();
    for (int p : fixed_off_diagonal_) values[p] = 0.0;
    for (int p : fixed_diagonal_) values[p] = 1.0;
    for (int v = 0; v < num_vertices_; ++v) {
      if (problem.is_fixed(v)) g->segment<3>(3 * v).setZero();
    }
  }
  if (whisper > 0) {  // for degrees of freedom no term references
    // In spans on the team (scattered reads of a large H wait on memory); a maximum is the
    // same in any order, so every thread count gives the same shift.
    double* values = H_.valuePtr();
    const int* at = diagonal_at_.data();
    const int64_t n = static_cast<int64_t>(diagonal_at_.size());
    const int64_t grain = std::max<int64_t>(1, SpanGrain(n));
    // Each piece's maximum (piece k begins at k * grain).
    std::vector<double> span_max(static_cast<size_t>((n + grain - 1) / grain + 1), 0.0);
    ParallelSpans(threads_, n, kParallelDiagonal, [&](int64_t begin, int64_t end) {
      double m = 0.0;
      for (int64_t i = begin; i < end; ++i) m = std::max(m, values[at[i]]);
      span_max[static_cast<size_t>(begin / grain)] = m;
    });
    const double max_diagonal = *std::max_element(span_max.begin(), span_max.end());
    const double add = whisper * max_diagonal;
    ParallelSpans(threads_, n, kParallelDiagonal, [&](int64_t begin, int64_t end) {
      for (int64_t i = begin; i < end; ++i) values[at[i]] += add;
    });
  }
}

}  // namespace energy
}  // namespace femreg
