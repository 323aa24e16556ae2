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
// block on top), z its rows. Columns go four at a time: one pass over the rows below a
// block of four updates them (forward) or forms their four dot products (backward), so z
// is read once per four columns. The rows go four at a time in GCC's vector types (two SSE
// registers each by default, one AVX register in the x86-64-v3 clone); a dot product keeps
// four lane sums added in a fixed order at the end, so the result does not depend on the
// clone (up to the fused multiply-adds the compiler forms).
// The helpers take and give them through pointers and references: a vector passed by
// value would have one calling convention in the AVX2 clone and another in the default one.
typedef double Double4 __attribute__((vector_size(32)));
typedef float Float4 __attribute__((vector_size(16)));

inline void Load4(const double* p, Double4* v) { __builtin_memcpy(v, p, sizeof(*v)); }
inline void Load4(const float* p, Double4* v) {
  Float4 f;
  __builtin_memcpy(&f, p, sizeof(f));
  *v = __builtin_convertvector(f, Double4);
}
inline void Store4(double* p, const Double4& v) { __builtin_memcpy(p, &v, sizeof(v)); }
inline double Sum(const Double4& v) { return (v[0] + v[1]) + (v[2] + v[3]); }
// Rows i..i+3 of z and of the four columns starting at c0 (nrow apart).
template <class Scalar>
inline void LoadRows(const Scalar* c0, int nrow, int i, const double* z, Double4* zi, Double4* l) {
  Load4(z + i, zi);
  for (int k = 0; k < 4; ++k) Load4(c0 + static_cast<int64_t>(k) * nrow + i, l + k);
}

template <class Scalar>
__attribute__((target_clones("arch=x86-64-v3", "default"))) void ForwardKernel(
    const Scalar* L, int nrow, int ncol, double* z) {
  int j0 = 0;
  for (; j0 + 4 <= ncol; j0 += 4) {
    const Scalar* c0 = L + static_cast<int64_t>(j0) * nrow;
    const Scalar* c1 = c0 + nrow;
    const Scalar* c2 = c1 + nrow;
    const Scalar* c3 = c2 + nrow;
    const double z0 = z[j0] / c0[j0];
    const double z1 = (z[j0 + 1] - c0[j0 + 1] * z0) / c1[j0 + 1];
    const double z2 = (z[j0 + 2] - c0[j0 + 2] * z0 - c1[j0 + 2] * z1) / c2[j0 + 2];
    const double z3 = (z[j0 + 3] - c0[j0 + 3] * z0 - c1[j0 + 3] * z1 - c2[j0 + 3] * z2) / c3[j0 + 3];
    z[j0] = z0;
    z[j0 + 1] = z1;
    z[j0 + 2] = z2;
    z[j0 + 3] = z3;
    int i = j0 + 4;
    for (; i + 4 <= nrow; i += 4) {
      Double4 zi, l[4];
      LoadRows(c0, nrow, i, z, &zi, l);
      Store4(z + i, zi - ((l[0] * z0 + l[1] * z1) + (l[2] * z2 + l[3] * z3)));
    }
    for (; i < nrow; ++i) {
      z[i] -= (static_cast<double>(c0[i]) * z0 + static_cast<double>(c1[i]) * z1) +
              (static_cast<double>(c2[i]) * z2 + static_cast<double>(c3[i]) * z3);
    }
  }
  for (int j = j0; j < ncol; ++j) {
    const Scalar* c = L + static_cast<int64_t>(j) * nrow;
    const double zj = z[j] / c[j];
    z[j] = zj;
    int i = j + 1;
    for (; i + 4 <= nrow; i += 4) {
      Double4 zi, l;
      Load4(z + i, &zi);
      Load4(c + i, &l);
      Store4(z + i, zi - l * zj);
    }
    for (; i < nrow; ++i) z[i] -= static_cast<double>(c[i]) * zj;
  }
}

// sum_{i in [begin, nrow)} c[i] z[i], in four lanes.
template <class Scalar>
inline double Dot(const Scalar* c, const double* z, int begin, int nrow) {
  Double4 a = {0.0, 0.0, 0.0, 0.0};
  int i = begin;
  for (; i + 4 <= nrow; i += 4) {
    Double4 l, zi;
    Load4(c + i, &l);
    Load4(z + i, &zi);
    a += l * zi;
  }
  for (int l = 0; i < nrow; ++i, ++l) a[l] += static_cast<double>(c[i]) * z[i];
  return Sum(a);
}

template <class Scalar>
__attribute__((target_clones("arch=x86-64-v3", "default"))) void BackwardKernel(
    const Scalar* L, int nrow, int ncol, double* z) {
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
    Double4 a0 = {0.0, 0.0, 0.0, 0.0}, a1 = a0, a2 = a0, a3 = a0;
    int i = j0 + 4;
    for (; i + 4 <= nrow; i += 4) {
      Double4 zi, l[4];
      LoadRows(c0, nrow, i, z, &zi, l);
      a0 += l[0] * zi;
      a1 += l[1] * zi;
      a2 += l[2] * zi;
      a3 += l[3] * zi;
    }
    for (int l = 0; i < nrow; ++i, ++l) {
      a0[l] += static_cast<double>(c0[i]) * z[i];
      a1[l] += static_cast<double>(c1[i]) * z[i];
      a2[l] += static_cast<double>(c2[i]) * z[i];
      a3[l] += static_cast<double>(c3[i]) * z[i];
    }
    const double s0 = Sum(a0), s1 = Sum(a1), s2 = Sum(a2), s3 = Sum(a3);
    const double z3 = (z[j0 + 3] - s3) / c3[j0 + 3];
    const double z2 = (z[j0 + 2] - s2 - c2[j0 + 3] * z3) / c2[j0 + 2];
    const double z1 = (z[j0 + 1] - s1 - c1[j0 + 2] * z2 - c1[j0 + 3] * z3) / c1[j0 + 1];
    const double z0 = (z[j0] - s0 - c0[j0 + 1] * z1 - c0[j0 + 2] * z2 - c0[j0 + 3] * z3) / c0[j0];
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
void SupernodalSolve<Scalar>::Forward(int s, const double* b, double* acc, double* y,
                                      double* z) const {
  const int k0 = super_[static_cast<size_t>(s)];
  const int ncol = super_[static_cast<size_t>(s) + 1] - k0;
  const int nrow = pi_[static_cast<size_t>(s) + 1] - pi_[static_cast<size_t>(s)];
  const int* rows = rows_.data() + pi_[static_cast<size_t>(s)];
  for (int j = 0; j < ncol; ++j) z[j] = b[k0 + j] - acc[k0 + j];
  for (int i = ncol; i < nrow; ++i) z[i] = 0.0;
  ForwardKernel(values_.data() + px_[static_cast<size_t>(s)], nrow, ncol, z);
  if (sign_.empty()) {
    for (int j = 0; j < ncol; ++j) y[k0 + j] = z[j];
  } else {  // L S L^T: S's sign on the forward result (the updates below took it unsigned)
    for (int j = 0; j < ncol; ++j) y[k0 + j] = static_cast<double>(sign_[static_cast<size_t>(k0 + j)]) * z[j];
  }
  for (int i = ncol; i < nrow; ++i) acc[rows[i]] -= z[i];
}

// Supernode s of L^T x = y, in place: its rows below hold their solution already.
template <class Scalar>
void SupernodalSolve<Scalar>::Backward(int s, double* y, double* z) const {
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
void SupernodalSolve<Scalar>::SolveTop(int num_groups, double* y) {
  double* acc = acc_[0].data();
  for (int s : top_) {
    for (int c = super_[static_cast<size_t>(s)]; c < super_[static_cast<size_t>(s) + 1]; ++c) {
      for (int g = 1; g < num_groups; ++g) acc[c] += acc_[static_cast<size_t>(g)][c];
    }
  }
  double* z = z_[0].data();
  for (int s : top_) Forward(s, b_.data(), acc, y, z);
  for (auto it = top_.rbegin(); it != top_.rend(); ++it) Backward(*it, y, z);
}

template <class Scalar>
void SupernodalSolve<Scalar>::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  const int* perm = perm_.data();
  for (int k = 0; k < n_; ++k) b_[k] = b[perm[k]];
  double* y = y_.data();
  const int num_groups = static_cast<int>(groups_.size());
  if (num_groups == 1) {
    double* acc = acc_[0].data();
    double* z = z_[0].data();
    acc_[0].setZero();
    for (int s : groups_[0]) Forward(s, b_.data(), acc, y, z);
    for (auto it = groups_[0].rbegin(); it != groups_[0].rend(); ++it) Backward(*it, y, z);
  } else if (threads_ == 1) {  // the team's steps below, one after the other
    for (int g = 0; g < num_groups; ++g) {
      acc_[static_cast<size_t>(g)].setZero();
      for (int s : groups_[static_cast<size_t>(g)]) {
        Forward(s, b_.data(), acc_[static_cast<size_t>(g)].data(), y, z_[static_cast<size_t>(g)].data());
      }
    }
    SolveTop(num_groups, y);
    for (int g = 0; g < num_groups; ++g) {
      const std::vector<int>& group = groups_[static_cast<size_t>(g)];
      for (auto it = group.rbegin(); it != group.rend(); ++it) Backward(*it, y, z_[static_cast<size_t>(g)].data());
    }
  } else {
    // The groups on femreg's workers (parallel/pool.h), the top on this thread between.
    const int team = std::min(threads_, num_groups);
    RunTasks(team, num_groups, [&](int g) {
      acc_[static_cast<size_t>(g)].setZero();
      for (int s : groups_[static_cast<size_t>(g)]) {
        Forward(s, b_.data(), acc_[static_cast<size_t>(g)].data(), y, z_[static_cast<size_t>(g)].data());
      }
    });
    SolveTop(num_groups, y);
    RunTasks(team, num_groups, [&](int g) {
      const std::vector<int>& group = groups_[static_cast<size_t>(g)];
      for (auto it = group.rbegin(); it != group.rend(); ++it) {
        Backward(*it, y, z_[static_cast<size_t>(g)].data());
      }
    });
  }
  x->resize(n_);
  for (int k = 0; k < n_; ++k) (*x)[perm[k]] = y[k];
}

template void SupernodalSolve<float>::Forward(int, const double*, double*, double*, double*) const;
template void SupernodalSolve<float>::Backward(int, double*, double*) const;
template void SupernodalSolve<float>::SolveTop(int, double*);
template void SupernodalSolve<float>::Solve(const Eigen::VectorXd&, Eigen::VectorXd*);
template void SupernodalSolve<double>::Forward(int, const double*, double*, double*, double*) const;
template void SupernodalSolve<double>::Backward(int, double*, double*) const;
template void SupernodalSolve<double>::SolveTop(int, double*);
template void SupernodalSolve<double>::Solve(const Eigen::VectorXd&, Eigen::VectorXd*);

}  // namespace fast_backend
}  // namespace femreg
