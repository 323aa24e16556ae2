// Solves with a CHOLMOD supernodal LL^T factor in the fast back end's own code, for PCG's
// preconditioner (one forward and one backward substitution per iteration).
//
// Those substitutions read all of L once each and do two flops per entry: their time is
// the time to stream L from memory (demo, nnz(L) 364k: 0.23 ms per pair through CHOLMOD;
// a 3.7k-vertex beam: ~3 ms). So the values are kept in `Scalar`, float in the back end:
// half the bytes. The vectors and every sum stay in double; what changes is L itself, by
// a relative 6e-8 per entry, far less than the difference between the kept factor and the
// matrix PCG solves (a factor of an earlier step's matrix), which PCG corrects anyway.
//
// In parallel: the supernodal elimination tree is cut into disjoint subtrees, grouped into
// one set per thread, and a "top" of the supernodes above them. The forward substitution
// runs the groups in parallel, each adding its updates of the top's rows into a vector of
// its own, then the top on one thread; the backward substitution runs the top first, then
// the groups in parallel (a supernode reads only its ancestors). No two threads write one
// entry, and the order of every sum is fixed by the cut, so a thread count gives the same
// result on every run.
#ifndef FEMREG_SOLVERS_FAST_SUPERNODAL_SOLVE_H_
#define FEMREG_SOLVERS_FAST_SUPERNODAL_SOLVE_H_

#include <cholmod.h>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace femreg {
namespace fast_backend {

template <class Scalar>
class SupernodalSolve {
 public:
  // Takes L's structure (again only when its symbolic analysis changed: `new_structure`)
  // and copies its values. False, and nothing kept, unless L is a supernodal LL^T factor
  // with int indices and real double values.
  bool Load(const cholmod_factor& L, bool new_structure, int threads);
  bool loaded() const { return loaded_; }
  // x = A^-1 b for the factorized A = P^T L L^T P. x may not alias b.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x);
  // The share of L's entries solved on one thread while the others wait: the top (0 on one
  // thread; 1 when no cut of the tree beats one thread).
  double serial_fraction() const { return serial_fraction_; }

 private:
  void Forward(int s, const double* b, double* acc, double* y, double* z) const;
  void Backward(int s, double* y, double* z) const;

  bool loaded_ = false;
  int n_ = 0;
  int threads_ = 1;
  std::vector<int> super_, pi_, rows_, perm_;
  std::vector<int64_t> px_;
  std::vector<Scalar> values_;
  // Per thread, its supernodes in ascending order (children before parents); the top.
  std::vector<std::vector<int>> groups_;
  std::vector<int> top_;
  double serial_fraction_ = 0.0;
  // Work vectors: the permuted right-hand side and solution, per thread an accumulator of
  // forward updates (n) and a supernode's buffer (its rows).
  Eigen::VectorXd b_, y_;
  std::vector<Eigen::VectorXd> acc_, z_;
};

extern template class SupernodalSolve<float>;
extern template class SupernodalSolve<double>;

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_SUPERNODAL_SOLVE_H_
