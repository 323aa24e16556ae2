// The supernodal solve's substitutions (supernodal_solve.h): L y = b and L^T x = y by
// supernodes, the groups of the tree's cut in parallel and the top after them, with dense
// kernels of four columns at a time.
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <type_traits>

#include "parallel/pool.h"
#include "parallel/threads.h"
#include "solvers/fast/supernodal_solve.h"

namespace femreg {
namespace fast_backend {

namespace {

// The dense kernels of one supernode: L its nrow x ncol block (column-major, the diagonal
// block on top, in Scalar), z its rows (in Work: double, or the factor's float). Columns go
// four at a time: one pass over the rows below a block of four updates them (forward) or
// forms their four dot products (backward), so z is read once per four columns. The rows go a
// vector at a time in GCC's vector types of 32 bytes (four doubles or eight floats: two SSE
// registers each by default, one AVX register in the x86-64-v3 clone; L's floats converted
// into a double vector); a dot product keeps its lane sums added in a fixed order at the end,
// so the result does not depend on the clone (up to the fused multiply-adds the compiler
// forms).
// The helpers take and give them through pointers and references: a vector passed by
// value would have one calling convention in the AVX2 clone and another in the default one.
template <class Work>
struct Lanes {
  static constexpr int kWidth = static_cast<int>(32 / sizeof(Work));
  typedef Work Vector __attribute__((vector_size(32)));
};
typedef Lanes<double>::Vector Double4;
typedef float Float4 __attribute__((vector_size(16)));

template <class Scalar, class Vector>
inline void Load(const Scalar* p, Vector* v) {
  static_assert(std::is_same<std::remove_reference_t<decltype((*v)[0])>, Scalar>::value,
                "a vector of another type than its entries: only float into double converts");
  __builtin_memcpy(v, p, sizeof(*v));
}
inline void Load(const float* p, Double4* v) {
  Float4 f;
  __builtin_memcpy(&f, p, sizeof(f));
  *v = __builtin_convertvector(f, Double4);
}
template <class Work, class Vector>
inline void Store(Work* p, const Vector& v) { __builtin_memcpy(p, &v, sizeof(v)); }
// Rows i.. of z and of the four columns c[0..3], a vector each, into separate vectors (an
// array of four made the float kernels slower: docs/notes/2026-12-04-float-substitutions.md).
template <class Scalar, class Work, class Vector>
inline void LoadRows(const Scalar* const c[4], int i, const Work* z, Vector* zi, Vector* l0,
                     Vector* l1, Vector* l2, Vector* l3) {
  Load(z + i, zi);
  Load(c[0] + i, l0);
  Load(c[1] + i, l1);
  Load(c[2] + i, l2);
  Load(c[3] + i, l3);
}
// The lanes' sum, adjacent pairs first: ((v0 + v1) + (v2 + v3)) + ((v4 + v5) + (v6 + v7)).
template <class Work, class Vector>
inline Work Sum(const Vector& v) {
  constexpr int kWidth = Lanes<Work>::kWidth;
  Work s[kWidth];
  for (int k = 0; k < kWidth; ++k) s[k] = v[k];
  for (int step = 1; step < kWidth; step *= 2) {
    for (int k = 0; k + step < kWidth; k += 2 * step) s[k] += s[k + step];
  }
  return s[0];
}

template <class Scalar, class Work>
__attribute__((target_clones("arch=x86-64-v3", "default"))) void ForwardKernel(
    const Scalar* L, int nrow, int ncol, Work* z) {
  typedef typename Lanes<Work>::Vector Vector;
  constexpr int kWidth = Lanes<Work>::kWidth;
  int j0 = 0;
  for (; j0 + 4 <= ncol; j0 += 4) {
    const Scalar* c0 = L + static_cast<int64_t>(j0) * nrow;
    const Scalar* c1 = c0 + nrow;
    const Scalar* c2 = c1 + nrow;
    const Scalar* c3 = c2 + nrow;
    const Scalar* const columns[4] = {c0, c1, c2, c3};
    const Work z0 = z[j0] / c0[j0];
    const Work z1 = (z[j0 + 1] - c0[j0 + 1] * z0) / c1[j0 + 1];
    const Work z2 = (z[j0 + 2] - c0[j0 + 2] * z0 - c1[j0 + 2] * z1) / c2[j0 + 2];
    const Work z3 = (z[j0 + 3] - c0[j0 + 3] * z0 - c1[j0 + 3] * z1 - c2[j0 + 3] * z2) / c3[j0 + 3];
    z[j0] = z0;
    z[j0 + 1] = z1;
    z[j0 + 2] = z2;
    z[j0 + 3] = z3;
    int i = j0 + 4;
    for (; i + kWidth <= nrow; i += kWidth) {
      Vector zi, l0, l1, l2, l3;
      LoadRows(columns, i, z, &zi, &l0, &l1, &l2, &l3);
      Store(z + i, zi - ((l0 * z0 + l1 * z1) + (l2 * z2 + l3 * z3)));
    }
    for (; i < nrow; ++i) {
      z[i] -= (static_cast<Work>(c0[i]) * z0 + static_cast<Work>(c1[i]) * z1) +
              (static_cast<Work>(c2[i]) * z2 + static_cast<Work>(c3[i]) * z3);
    }
  }
  for (int j = j0; j < ncol; ++j) {
    const Scalar* c = L + static_cast<int64_t>(j) * nrow;
    const Work zj = z[j] / c[j];
    z[j] = zj;
    int i = j + 1;
    for (; i + kWidth <= nrow; i += kWidth) {
      Vector zi, l;
      Load(z + i, &zi);
      Load(c + i, &l);
      Store(z + i, zi - l * zj);
    }
    for (; i < nrow; ++i) z[i] -= static_cast<Work>(c[i]) * zj;
  }
}

// sum_{i in [begin, nrow)} c[i] z[i], in the lanes.
template <class Scalar, class Work>
inline Work Dot(const Scalar* c, const Work* z, int begin, int nrow) {
  typedef typename Lanes<Work>::Vector Vector;
  constexpr int kWidth = Lanes<Work>::kWidth;
  Vector a = {};
  int i = begin;
  for (; i + kWidth <= nrow; i += kWidth) {
    Vector l, zi;
    Load(c + i, &l);
    Load(z + i, &zi);
    a += l * zi;
  }
  for (int l = 0; i < nrow; ++i, ++l) a[l] += static_cast<Work>(c[i]) * z[i];
  return Sum<Work>(a);
}

template <class Scalar, class Work>
__attribute__((target_clones("arch=x86-64-v3", "default"))) void BackwardKernel(
    const Scalar* L, int nrow, int ncol, Work* z) {
  typedef typename Lanes<Work>::Vector Vector;
  constexpr int kWidth = Lanes<Work>::kWidth;
  // The columns past the last full block of four, last first; then the blocks.
  const int blocks_end = ncol - ncol % 4;
  for (int j = ncol - 1; j >= blocks_end; --j) {
    const Scalar* c = L + static_cast<int64_t>(j) * nrow;
    z[j] = (z[j] - Dot(c, z, j + 1, nrow)) / c[j];
  }
  for (int j0 = blocks_end - 4; j0 >= 0; j0 -= 4) {
    const Scalar* c0 = L + static_cast<int64_t>(j0) * nrow;
    const Scalar* c1 = c0 + nrow;
    const Scalar* c2 = c1 + nrow;
    const Scalar* c3 = c2 + nrow;
    const Scalar* const columns[4] = {c0, c1, c2, c3};
    Vector a0 = {}, a1 = {}, a2 = {}, a3 = {};
    int i = j0 + 4;
    for (; i + kWidth <= nrow; i += kWidth) {
      Vector zi, l0, l1, l2, l3;
      LoadRows(columns, i, z, &zi, &l0, &l1, &l2, &l3);
      a0 += l0 * zi;
      a1 += l1 * zi;
      a2 += l2 * zi;
      a3 += l3 * zi;
    }
    for (int l = 0; i < nrow; ++i, ++l) {
      a0[l] += static_cast<Work>(c0[i]) * z[i];
      a1[l] += static_cast<Work>(c1[i]) * z[i];
      a2[l] += static_cast<Work>(c2[i]) * z[i];
      a3[l] += static_cast<Work>(c3[i]) * z[i];
    }
    const Work s0 = Sum<Work>(a0), s1 = Sum<Work>(a1), s2 = Sum<Work>(a2), s3 = Sum<Work>(a3);
    const Work z3 = (z[j0 + 3] - s3) / c3[j0 + 3];
    const Work z2 = (z[j0 + 2] - s2 - c2[j0 + 3] * z3) / c2[j0 + 2];
    const Work z1 = (z[j0 + 1] - s1 - c1[j0 + 2] * z2 - c1[j0 + 3] * z3) / c1[j0 + 1];
    const Work z0 = (z[j0] - s0 - c0[j0 + 1] * z1 - c0[j0 + 2] * z2 - c0[j0 + 3] * z3) / c0[j0];
    z[j0] = z0;
    z[j0 + 1] = z1;
    z[j0 + 2] = z2;
    z[j0 + 3] = z3;
  }
}

}  // namespace

// Supernode s of L y = b: its columns' values from b less the updates `acc` holds, then
// its own updates of the rows below into `acc`.
template <class Scalar>
template <class Work>
void SupernodalSolve<Scalar>::Forward(int s, const Work* b, Work* acc, Work* y, Work* z) const {
  const int k0 = super_[static_cast<size_t>(s)];
  const int ncol = super_[static_cast<size_t>(s) + 1] - k0;
  const int nrow = pi_[static_cast<size_t>(s) + 1] - pi_[static_cast<size_t>(s)];
  const int* rows = rows_.data() + pi_[static_cast<size_t>(s)];
  for (int j = 0; j < ncol; ++j) z[j] = b[k0 + j] - acc[k0 + j];
  for (int i = ncol; i < nrow; ++i) z[i] = 0;
  ForwardKernel(values_.data() + px_[static_cast<size_t>(s)], nrow, ncol, z);
  if (sign_.empty()) {
    for (int j = 0; j < ncol; ++j) y[k0 + j] = z[j];
  } else {  // L S L^T: S's sign on the forward result (the updates below took it unsigned)
    for (int j = 0; j < ncol; ++j) y[k0 + j] = static_cast<Work>(sign_[static_cast<size_t>(k0 + j)]) * z[j];
  }
  for (int i = ncol; i < nrow; ++i) acc[rows[i]] -= z[i];
}

// Supernode s of L^T x = y, in place: its rows below hold their solution already.
template <class Scalar>
template <class Work>
void SupernodalSolve<Scalar>::Backward(int s, Work* y, Work* z) const {
  const int k0 = super_[static_cast<size_t>(s)];
  const int ncol = super_[static_cast<size_t>(s) + 1] - k0;
  const int nrow = pi_[static_cast<size_t>(s) + 1] - pi_[static_cast<size_t>(s)];
  const int* rows = rows_.data() + pi_[static_cast<size_t>(s)];
  for (int j = 0; j < ncol; ++j) z[j] = y[k0 + j];
  for (int i = ncol; i < nrow; ++i) z[i] = y[rows[i]];
  BackwardKernel(values_.data() + px_[static_cast<size_t>(s)], nrow, ncol, z);
  for (int j = 0; j < ncol; ++j) y[k0 + j] = z[j];
}

// The top: the groups' updates of its rows summed (in group order), then its forward and
// backward substitutions.
template <class Scalar>
template <class Work>
void SupernodalSolve<Scalar>::SolveTop(int num_groups, Workspace<Work>* w) {
  Work* acc = w->acc[0].data();
  for (int s : top_) {
    for (int c = super_[static_cast<size_t>(s)]; c < super_[static_cast<size_t>(s) + 1]; ++c) {
      for (int g = 1; g < num_groups; ++g) acc[c] += w->acc[static_cast<size_t>(g)][c];
    }
  }
  Work* y = w->y.data();
  Work* z = w->z[0].data();
  for (int s : top_) Forward(s, w->b.data(), acc, y, z);
  for (auto it = top_.rbegin(); it != top_.rend(); ++it) Backward(*it, y, z);
}

template <class Scalar>
void SupernodalSolve<Scalar>::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  if constexpr (std::is_same<Scalar, float>::value) {
    if (single_work_) {
      if (single_.acc.empty()) single_.Size(groups_.size(), n_, max_rows_);  // reset by TakeStructure
      SolveIn(b, x, &single_);
      return;
    }
  }
  SolveIn(b, x, &work_);
}

template <class Scalar>
template <class Work>
void SupernodalSolve<Scalar>::SolveIn(const Eigen::VectorXd& b, Eigen::VectorXd* x, Workspace<Work>* w) {
  const int* perm = perm_.data();
  for (int k = 0; k < n_; ++k) w->b[k] = static_cast<Work>(b[perm[k]]);
  Work* y = w->y.data();
  const Work* bb = w->b.data();
  const int num_groups = static_cast<int>(groups_.size());
  auto forward_group = [&](int g) {
    Work* acc = w->acc[static_cast<size_t>(g)].data();
    Work* z = w->z[static_cast<size_t>(g)].data();
    w->acc[static_cast<size_t>(g)].setZero();
    for (int s : groups_[static_cast<size_t>(g)]) Forward(s, bb, acc, y, z);
  };
  auto backward_group = [&](int g) {
    const std::vector<int>& group = groups_[static_cast<size_t>(g)];
    Work* z = w->z[static_cast<size_t>(g)].data();
    for (auto it = group.rbegin(); it != group.rend(); ++it) Backward(*it, y, z);
  };
  if (num_groups == 1) {
    forward_group(0);
    backward_group(0);
  } else if (threads_ == 1) {  // the team's steps below, one after the other
    for (int g = 0; g < num_groups; ++g) forward_group(g);
    SolveTop(num_groups, w);
    for (int g = 0; g < num_groups; ++g) backward_group(g);
  } else {
    // The groups on femreg's workers (parallel/pool.h), the top on this thread between.
    const int team = std::min(threads_, num_groups);
    RunTasks(team, num_groups, forward_group);
    SolveTop(num_groups, w);
    RunTasks(team, num_groups, backward_group);
  }
  x->resize(n_);
  for (int k = 0; k < n_; ++k) (*x)[perm[k]] = static_cast<double>(y[k]);
}

template void SupernodalSolve<float>::Solve(const Eigen::VectorXd&, Eigen::VectorXd*);
template void SupernodalSolve<double>::Solve(const Eigen::VectorXd&, Eigen::VectorXd*);

}  // namespace fast_backend
}  // namespace femreg
