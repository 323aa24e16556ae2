// The one assembler: the gradient and a Hessian of an energy::Problem at x, scattered into a
// fixed sparse pattern, for every block type of the registry. The fast back end assembles its
// Gauss-Newton systems with it, the forward solve its Newton systems (the exact Hessian, or
// its projection: energy/term.h, Curvature).
//
// The pattern is 3 #V by 3 #V, both triangles, with full 3x3 vertex blocks for the problem's
// coupling (the meshes' tetrahedra), the diagonal and pairs added later (blocks whose stencil
// reaches beyond the coupling, e.g. contacts between objects, or a caller's AddBlock), so that
// a factorization's symbolic analysis holds until the topology changes (pattern_revision).
// Fixed vertices (Problem::fixed) get identity rows and columns and no gradient.
//
// On several threads the vertices are split into one compact region per thread (runs of a
// Morton curve through them): blocks that straddle two regions are linearized in parallel
// into a buffer; then each thread goes through its blocks in ascending order, linearizing and
// adding those whose stencil lies in its region and adding the parts of the straddling ones
// that land in it. Each entry receives its terms in block order, as on one thread, so the
// result does not depend on the thread count.
#ifndef FEMREG_ENERGY_ASSEMBLER_H_
#define FEMREG_ENERGY_ASSEMBLER_H_

#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "energy/problem.h"
#include "femreg/energy.h"
#include "femreg/mesh.h"

namespace femreg {
namespace energy {

// Whether a compressed matrix has the assembler's layout: each vertex's three columns of one
// length, a multiple of 3, with the same rows, and each block's three rows consecutive from a
// multiple of 3.
template <class Scalar>
bool FullVertexBlocks(const Eigen::SparseMatrix<Scalar>& H) {
  if (!H.isCompressed() || H.cols() % 3 != 0) return false;
  const int* outer = H.outerIndexPtr();
  const int* inner = H.innerIndexPtr();
  for (Eigen::Index b = 0; 3 * b < H.cols(); ++b) {
    const int begin = outer[3 * b], stride = outer[3 * b + 1] - begin;
    if (stride % 3 != 0 || outer[3 * b + 2] - outer[3 * b + 1] != stride ||
        outer[3 * b + 3] - outer[3 * b + 2] != stride) {
      return false;
    }
    for (int k = 0; k < stride; ++k) {
      const int row = inner[begin + k];
      if (row != inner[begin + k - k % 3] + k % 3 || inner[begin + k - k % 3] % 3 != 0 ||
          inner[begin + stride + k] != row || inner[begin + 2 * stride + k] != row) {
        return false;
      }
    }
  }
  return true;
}

// Per 3x3 block of a matrix in that layout, column block by column block (column block b's
// blocks from its first entry / 9 on): the block's row vertex (Assembler::block_rows).
template <class Scalar>
std::vector<int> BlockRowVertices(const Eigen::SparseMatrix<Scalar>& H) {
  std::vector<int> rows(static_cast<size_t>(H.nonZeros() / 9));
  const int* outer = H.outerIndexPtr();
  const int* inner = H.innerIndexPtr();
  for (Eigen::Index b = 0; 3 * b < H.cols(); ++b) {
    for (int k = outer[3 * b]; k < outer[3 * b + 1]; k += 3) {
      rows[static_cast<size_t>(outer[3 * b] / 9 + (k - outer[3 * b]) / 3)] = inner[k] / 3;
    }
  }
  return rows;
}

class Assembler {
 public:
  explicit Assembler(int threads = 1) : threads_(threads) {}
  void set_threads(int threads) { threads_ = threads; }
  int threads() const { return threads_; }
  // Assemble only the sets of these groups (a mask of 1 << TermGroup; default all): equilibrium
  // registration assembles its potential's Hessian and its objective's apart.
  void set_groups(uint32_t mask) { groups_ = mask; }

  // Fits the pattern to the problem: built anew when its vertex count or coupling changed
  // (the thread regions from the positions x), widened by every block's stencil pairs and
  // by `pairs` (vertex pairs a caller will AddBlock) outside it. Returns how often the
  // pattern was (re)built: 0 when it held.
  int Prepare(const Problem& problem, const Vertices& x,
              const std::vector<std::pair<int, int>>& pairs = {});
  // Changes whenever the pattern is rebuilt (a factorization's analysis is then stale).
  uint64_t pattern_revision() const { return pattern_revision_; }

  // The Gauss-Newton system (energy/term.h's Linearize; a kNewtonCurvature block type's
  // projected Newton Hessian instead) at x into H and g, the fixed rows
  // applied and a whisper of Tikhonov (1e-12 of the largest diagonal entry) for degrees of
  // freedom no term references. first: the sets whose Jacobian is constant and that have
  // no robust loss are assembled anew and kept (later calls reuse their H part, within one
  // Solve), and *energy (if given) is the energy at x from the same linearization, added
  // as Problem::Evaluate adds it.
  void AssembleGaussNewton(const Problem& problem, const Vertices& x, bool first, Eigen::VectorXd* g,
                           EnergyTerms* energy = nullptr);
  // The exact Hessian or its projection (LinearizeSecondOrder) and the gradient at x; with
  // with_hessian false, the gradient only (H untouched). Returns the energy, added as
  // Problem::Evaluate adds it. The fixed rows are not applied: AddBlock what else belongs
  // to H, then Finish.
  double AssembleSecondOrder(const Problem& problem, const Vertices& x, Curvature curvature,
                             bool with_hessian, Eigen::VectorXd* g);
  // Adds M to the block of vertices (a, b) and M^T to (b, a) when a != b; false (nothing
  // added) when the pair is not in the pattern (give it to Prepare). Not thread-safe.
  bool AddBlock(int a, int b, const Eigen::Matrix3d& M);
  // Identity rows and columns for the problem's fixed vertices, no gradient there; adds
  // `whisper` times the largest diagonal entry to the diagonal.
  void Finish(const Problem& problem, double whisper, Eigen::VectorXd* g);

  Eigen::SparseMatrix<double>& H() { return H_; }
  const Eigen::SparseMatrix<double>& H() const { return H_; }
  // Per column, where its diagonal entry sits in H's values.
  const std::vector<int>& diagonal_at() const { return diagonal_at_; }
  // Per 3x3 block of H, column block by column block (vertex b's blocks from its first entry
  // / 9 on): the block's row vertex. A product can read these instead of H's per-entry rows.
  const std::vector<int>& block_rows() const { return block_rows_; }
  int num_vertices() const { return num_vertices_; }

  // Where the 3x3 block (a, b) of the system sits in the values of a column-major matrix
  // with full 3x3 blocks: entry (3a + i, 3b + j) is at offset + j * stride + i.
  struct Slot {
    int offset = -1;
    int stride = 0;
  };

 private:
  // Per set revision: each block's slots (#blocks * n * n), and for the parallel assembly
  // those whose vertices two threads own (straddling), and per thread t its blocks in
  // ascending order (interior[t]): b for one whose every vertex it owns, ~k for the k-th
  // straddling one that has a vertex of its.
  struct SetCache {
    std::vector<Slot> slots;
    bool used = false;
    std::vector<std::vector<int>> interior;
    std::vector<int> straddling;
  };
  void ResetPattern(const Problem& problem, const Vertices& x);
  void BuildPattern();
  void OrderVertices(const Vertices& x);
  Slot Find(int a, int b) const;
  // The cache of a set; pairs outside the pattern are added to *missing.
  template <class Set>
  SetCache& CacheOf(const Set& set, std::vector<std::pair<int, int>>* missing);
  // Adds the blocks of the sets for which take(set) holds: gradient always, Hessian when
  // hessian(set), linearized by linearize(block, loss, out, with_hessian). With set_energy:
  // the energy of each set taken, at its place in ForEachSet's order. A set of at least
  // `parallel_work` 3x3 blocks (#blocks x n^2) is assembled on the threads.
  template <class Take, class WithHessian, class Linearizer>
  void Accumulate(const Problem& problem, const Vertices& x, Take take, WithHessian hessian,
                  Linearizer linearize, Eigen::VectorXd* g, std::vector<double>* set_energy,
                  int64_t parallel_work);
  // The problem's nodal volume (if any, and if the elastic group is assembled): adds its
  // gradient to *g and its Hessian to H; returns its energy.
  double AddNodalVolume(const Problem& problem, const Vertices& x, Curvature curvature,
                        bool with_hessian, Eigen::VectorXd* g);
  // The per-set energies of Accumulate added up by group, as Problem::Evaluate does.
  EnergyTerms SumByGroup(const Problem& problem, const std::vector<double>& set_energy) const;

  int threads_ = 1;
  uint32_t groups_ = ~0u;
  int num_vertices_ = -1;
  uint64_t coupling_revision_ = 0;
  uint64_t pattern_revision_ = 0;
  std::vector<std::array<int, 4>> cells_;       // the coupling the pattern was built from
  std::vector<std::pair<int, int>> extra_pairs_;  // a < b
  Eigen::SparseMatrix<double> H_;
  std::vector<int> diagonal_at_;
  std::vector<int> block_rows_;
  // The thread that owns each vertex: a Morton curve through the positions when the pattern
  // was made, cut into `threads` runs of equal length. Meshes from mesh generators number
  // their vertices in no spatial order, and with a range of vertex numbers per thread most
  // of their elements would straddle two threads (docs/notes: the assembler's regions).
  std::vector<int> vertex_owner_;
  int owner_threads_ = 0;  // the thread count vertex_owner_ was cut for
  std::vector<double> scratch_;  // the straddling blocks' linearizations
  std::map<uint64_t, SetCache> cache_;
  // The slots of the 2-, 3- and 4-vertex stencils met on this pattern (a key of the stencil ->
  // their n * n slots at that offset of stencil_pool_): the data terms' sets are made anew
  // every outer iteration, their blocks mostly on surface triangles met before.
  std::unordered_map<uint64_t, int> stencil_slots_;
  std::vector<Slot> stencil_pool_;
  std::vector<double> block_values_;  // Accumulate's, of one set
  std::vector<double> set_energy_;
  // The part of H that is constant within one Solve (AssembleGaussNewton's first).
  std::vector<double> constant_values_;
  // The fixed flags the lists below were made for, and where H holds the entries of fixed
  // rows and columns (off the diagonal: 0; on it: 1).
  std::vector<char> fixed_for_;
  std::vector<int> fixed_off_diagonal_, fixed_diagonal_;
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_ASSEMBLER_H_
