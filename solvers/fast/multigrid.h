// Smoothed-aggregation algebraic multigrid: the fast back end's preconditioner for large meshes,
// where a sparse Cholesky factor's fill (and the time to stream it once per PCG iteration) grows
// faster than the mesh. One V-cycle here costs a few products with the system, so its cost grows
// with the mesh (docs/dev/fast-backend.md, docs/notes/2026-11-28-figures-from-code-comments.md).
//
// The hierarchy (Vaněk, Mandel and Brezina's smoothed aggregation, as in ML and PyAMG's
// smoothed_aggregation_solver, written here from the method):
//  - nodes: at the finest level the mesh's vertices (3 unknowns each), below the aggregates
//    of the level above (up to 6 unknowns each);
//  - strength: node b is a neighbour of a where the block A_ab is not negligible against
//    the diagonal blocks; nodes without neighbours (fixed vertices, vertices no term holds)
//    are left to the smoother;
//  - aggregation: greedy, a node and its neighbours, then the rest joined to a neighbouring
//    aggregate, then what is left in aggregates of its own;
//  - near null space: the six rigid motions of the vertex positions, restricted to each
//    aggregate and orthonormalized there (their coefficients are the next level's);
//  - prolongator: that tentative one smoothed by one step of block-Jacobi, P = (I - 4/3 D^-1 A /
//    lambda_max) T, and the coarse system P^T A P, both products formed by node blocks (Galerkin
//    below: dense blocks of fixed size in the inner loops, rows in parallel; faster than Eigen's
//    general sparse products (docs/notes/2026-11-28-figures-from-code-comments.md));
//  - smoother: Chebyshev polynomials of degree 2 in D^-1 A (block Jacobi: each node's
//    diagonal block inverted), on [lambda_max / 30, 1.1 lambda_max], the same before and
//    after the coarse correction, so that a V-cycle is a symmetric positive definite
//    operator (a preconditioner for conjugate gradients);
//  - the coarsest level (500 unknowns or fewer, unless coarsening stalls): its dense
//    inverse (from an LDL^T).
// Kept across steps: the caller passes each new system (SetFinest: the finest level's
// residuals and block-Jacobi inverses use it) and refreshes the finest smoother's eigenvalue
// bound for it when PCG says the V-cycle is not positive definite (RefreshFinest).
// Products run on `threads` threads from a size on (gathers over columns of symmetric
// matrices: no races, and the same sums on any thread count).
#ifndef FEMREG_SOLVERS_FAST_MULTIGRID_H_
#define FEMREG_SOLVERS_FAST_MULTIGRID_H_

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {
namespace fast_backend {

class Multigrid {
 public:
  // Builds the hierarchy of A (3 #V by 3 #V, symmetric, both triangles stored, column-major
  // and compressed, full 3x3 vertex blocks with sorted rows: the back end's system, whose
  // products are BlockProduct's) with the rigid motions of `positions` (#V by 3) as its near
  // null space. False (and nothing kept) if A has no unknowns, is not compressed or is not
  // positive on its diagonal.
  bool Build(const Eigen::SparseMatrix<double>& A,
             const Vertices& positions, int threads);
  bool built() const { return !levels_.empty(); }
  // The finest smoother's eigenvalue bound anew, for the system last given (SetFinest takes
  // its block-Jacobi inverses): a hierarchy kept across steps smooths with the current
  // system, and its Chebyshev interval must cover that system's spectrum (else the V-cycle
  // is not positive definite). False if there is no hierarchy.
  bool RefreshFinest();
  // The current system at the finest level: A, a later system on the pattern the hierarchy
  // was built on, whose values Apply's finest products and block-Jacobi inverses use from
  // here on (Build takes its own; the eigenvalue bound stays the last one's until
  // RefreshFinest). Call it whenever the system's values change. False if A's pattern is not the
  // hierarchy's (nothing changes then), or if a diagonal block of A is not positive
  // definite (the hierarchy dropped).
  bool SetFinest(const Eigen::SparseMatrix<double>& A);
  // z = M^-1 r: one V-cycle from z = 0, on the system last given (Build or SetFinest); z
  // may not alias r.
  void Apply(const Eigen::VectorXd& r, Eigen::VectorXd* z);
  int num_levels() const { return static_cast<int>(levels_.size()); }
  // The unknowns of all levels over the finest one's, and likewise the stored entries.
  double grid_complexity() const;
  double operator_complexity() const;

  // (The hierarchy's construction and the V-cycle's storage below the finest level, see
  // Level; public for their tests.) A block-sparse matrix by rows of
  // nodes: row node r's blocks are [begin[r], begin[r + 1]), in increasing column node;
  // block q is column node col[q]'s, its row_size[r] x col_size[col[q]] values column-major
  // at values[at[q]].
  struct BlockRows {
    std::vector<int> row_size, col_size;
    std::vector<int> begin = {0};
    std::vector<int> col, at;
    std::vector<double> values;
  };

  // M (rows by cols, its unknowns grouped into row and column nodes) as dense column-major
  // blocks, by column node; Multiply gives y = M^T x (for a symmetric M, M x).
  struct NodeBlocks {
    int rows = 0, cols = 0;
    std::vector<int> col_begin;    // the column nodes' first unknowns, and cols
    std::vector<int> block_begin;  // column node c's blocks: [block_begin[c], block_begin[c + 1])
    std::vector<int> row_first;    // per block: its row node's first unknown
    std::vector<int> row_count;    // per block: its row node's unknowns
    std::vector<int> value_at;     // per block: its row_count x (column node's size) values
    std::vector<int> rows_of;      // per column node: its blocks' row count if all share one, else 0
    std::vector<uint16_t> values;  // bfloat16 (multigrid_internal::ToBfloat16)
    // From a column-major M with both partitions (the nodes' first unknowns, then the size).
    void Assign(const Eigen::SparseMatrix<double>& M, const std::vector<int>& row_nodes,
                const std::vector<int>& col_nodes);
    // The same from M^T by node blocks (R's row nodes are M's column nodes).
    void AssignTransposed(const BlockRows& R, const std::vector<int>& row_nodes,
                          const std::vector<int>& col_nodes);
    void Multiply(const Eigen::VectorXd& x, int threads, Eigen::VectorXd* y);
    std::vector<float> x_float;  // Multiply's x in single precision
  };

  // One level's smoothed prolongator and coarse system, by node blocks: with T the tentative
  // prolongator (a row node's block, if any, in its aggregate's column node), A symmetric
  // (column-major, both triangles, nodes of node_begin) and D^-1 its nodes' inverted
  // diagonal blocks (node k's at dinv[dinv_at[k]], column-major),
  //   P = T - omega D^-1 A T,   A_c = P^T A P (made symmetric: (A_c + A_c^T) / 2),
  // P and P^T by node blocks, A_c column-major (stored by whole node blocks, rows sorted).
  // Rows run on `threads` threads, each summed in the same order on any thread count.
  // False if T has a row node without A's diagonal block.
  static bool Galerkin(const Eigen::SparseMatrix<double>& A, const std::vector<int>& node_begin,
                       const BlockRows& T, const std::vector<int>& dinv_at,
                       const std::vector<double>& dinv, double omega, int threads, BlockRows* P,
                       BlockRows* Pt, Eigen::SparseMatrix<double>* Ac);

 private:
  // The V-cycle reads its matrices in bfloat16 (float's range, 8 significant bits): its
  // products stream them from memory, and 2 bytes a value are a quarter of double's. The
  // vectors stay in double. A matrix whose values are rounded is still symmetric: what
  // changes is the operator itself, by up to 4e-3 relative per entry, less than what
  // separates it from A^-1 (PCG in double solves with A itself); P and P^T hold the same
  // rounded numbers, so the V-cycle stays symmetric. The products sum in float (with SSE 4
  // lanes at a time; FloatBlockProduct and GatherNodeFloat in the .cc files), which leaves
  // the V-cycle symmetric to ~1e-8 relative rather than to double round-off: still positive
  // definite, and far inside what PCG tolerates at its 1e-2 (mixed-precision AMG, e.g.
  // AmgX's float preconditioner for double solves, does the same). Level 0's system keeps
  // the back end's layout, its products reading one row vertex per 3x3 block (block_rows)
  // and not the per-entry indices (A_h, multigrid_internal::RoundToBfloat16): about 2.4 bytes
  // an entry. The coarse systems and the prolongators are stored as dense blocks between
  // nodes (an aggregate's up to 6 unknowns, a vertex's 3), one row index per block: about
  // 2.2-2.5 bytes an entry. Both instead of 12 with double values and an index per entry,
  // with inner loops of fixed length (docs/notes/2026-12-05-bfloat16-level-0.md,
  // docs/notes/2026-12-06-bfloat16-transfers.md).

  struct Level {
    Eigen::SparseMatrix<double> A;   // while building, below level 0 (level 0: the caller's)
    // Level 0: the V-cycle's copy of the last system given, its column starts (the back
    // end's layout, compressed) and values in bfloat16 (RoundToBfloat16), its blocks' rows
    // (energy::BlockRowVertices).
    std::vector<int> outer;
    std::vector<uint16_t> A_h;
    std::vector<int> block_rows;
    NodeBlocks A_b;                  // below level 0: the V-cycle's system
    int nonzeros = 0;               // of A (level 0's too)
    std::vector<int> node_begin;    // the unknowns of node k: [node_begin[k], node_begin[k + 1])
    std::vector<int> dinv_at;       // node k's inverted diagonal block in dinv
    std::vector<double> dinv;
    double lambda_max = 1.0;        // of D^-1 A
    // To the next level: P (this level's unknowns by the next's) and its transpose, so
    // that both products are gathers.
    NodeBlocks P_b, Pt_b;
    // Work vectors.
    Eigen::VectorXd x, b, r, d, ad;
  };

  // Level l's block-Jacobi inverses and lambda_max from A (its diagonal blocks' Frobenius
  // norms out); false if a diagonal block is not positive definite.
  bool PrepareSmoother(int l, const Eigen::SparseMatrix<double>& A, std::vector<double>* diagonal_norm);
  // Its two parts: the block-Jacobi inverses (and the diagonal blocks' norms), and
  // lambda_max of D^-1 A with the level's current system.
  bool InvertDiagonalBlocks(int l, const Eigen::SparseMatrix<double>& A, std::vector<double>* diagonal_norm);
  void EstimateLambdaMax(int l);
  void Product(int level, const Eigen::VectorXd& v, Eigen::VectorXd* y);
  void BlockJacobi(const Level& L, const Eigen::VectorXd& r, Eigen::VectorXd* z) const;
  // Chebyshev smoothing of A x = b at `level` from *x (zero_start: *x is 0).
  void Smooth(int level, bool zero_start);
  void Cycle(int level);

  int threads_ = 1;
  std::vector<Level> levels_;
  Eigen::MatrixXd coarse_inverse_;  // the coarsest level's A^-1 (dense)
  std::vector<float> v4_;           // level 0's product: its vector in float, 4 per vertex
};

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_MULTIGRID_H_
