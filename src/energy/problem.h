// The energy of one frame (or one outer iteration) as the sum of its term sets, which both
// back ends minimize (solvers/backend.h).
//
// Registering a new block type: write it (one header, see energy/term.h for what it provides)
// and add it to `Problem::Sets` below. Both back ends then take it: the Ceres back end through
// its generic cost adapter, the fast back end through its generic assembler, the tests
// through the generic derivative checks (tests/energy_test.cc).
#ifndef FEMREG_ENERGY_PROBLEM_H_
#define FEMREG_ENERGY_PROBLEM_H_

#include <array>
#include <memory>
#include <tuple>
#include <vector>

#include "energy/barrier.h"
#include "energy/contact.h"
#include "energy/data.h"
#include "energy/elastic.h"
#include "energy/equilibrium.h"
#include "energy/free_space.h"
#include "energy/friction.h"
#include "energy/load.h"
#include "energy/term.h"
#include "femreg/energy.h"
#include "femreg/mesh.h"

namespace femreg {
namespace energy {

class NodalVolume;

class Problem {
 public:
  // The registry: one vector of sets per block type.
  using Sets = std::tuple<std::vector<TermSet<ElasticElement>>, std::vector<TermSet<NeoHookeanElement>>,
                          std::vector<TermSet<InversionBarrier>>, std::vector<TermSet<EdgeSpring>>,
                          std::vector<TermSet<PointToPoint<1>>>, std::vector<TermSet<PointToPoint<3>>>,
                          std::vector<TermSet<PointToPlane<1>>>, std::vector<TermSet<PointToPlane<3>>>,
                          std::vector<TermSet<PointToPoint<4>>>, std::vector<TermSet<PointToPlane<4>>>,
                          std::vector<TermSet<ContactPenalty<3>>>,
                          std::vector<TermSet<ContactPenalty<6>>>, std::vector<TermSet<ContactPenalty<4>>>,
                          std::vector<TermSet<Friction<3>>>, std::vector<TermSet<Friction<6>>>,
                          std::vector<TermSet<Friction<4>>>, std::vector<TermSet<ExternalLoad>>,
                          std::vector<TermSet<FreeSpacePenalty>>>;

  // Sets the number of vertices and empties the problem.
  void Reset(int num_vertices);
  int num_vertices() const { return num_vertices_; }

  // A new, empty set of blocks of type T; the reference holds until the next AddSet of the
  // same type or Clear.
  template <class T>
  TermSet<T>& AddSet(TermGroup group, const Loss& loss = Loss()) {
    auto& sets = std::get<std::vector<TermSet<T>>>(sets_);
    sets.emplace_back(group, loss);
    return sets.back();
  }
  // Every set of block type T, to change blocks in place (their weights).
  template <class T>
  std::vector<TermSet<T>>& SetsOf() {
    return std::get<std::vector<TermSet<T>>>(sets_);
  }
  template <class T>
  const std::vector<TermSet<T>>& SetsOf() const {
    return std::get<std::vector<TermSet<T>>>(sets_);
  }
  // Removes every set of the group (the blocks that change per frame or per iteration).
  void Clear(TermGroup group);

  // Calls f(set) for every set, elastic group first, then temporal, anchor, data, collision
  // then loads (the order a Ceres problem adds its residual blocks in), each group in registry order.
  template <class F>
  void ForEachSet(F&& f) const {
    for (int g = 0; g < kNumTermGroups; ++g) {
      std::apply([&](const auto&... vectors) { (VisitGroup(vectors, static_cast<TermGroup>(g), f), ...); },
                 sets_);
    }
  }

  // Vertices held where they are (hard anchors): #V flags, or empty.
  std::vector<char>& fixed() { return fixed_; }
  const std::vector<char>& fixed() const { return fixed_; }
  bool is_fixed(int v) const { return !fixed_.empty() && fixed_[v]; }

  // The vertex groups that blocks may couple, e.g. the meshes' tetrahedra: a back end that
  // assembles a sparse system starts its pattern from them. `coupling_revision` changes with
  // them (a topology change).
  void SetCoupling(std::vector<std::array<int, 4>> cells);
  const std::vector<std::array<int, 4>>& coupling() const { return coupling_; }
  uint64_t coupling_revision() const { return coupling_revision_; }

  // Equilibrium registration (energy/equilibrium.h): the physics groups' energy is then not
  // minimized; its gradient's penalty is (EnergyTerms::equilibrium). Null: off.
  void SetEquilibrium(std::shared_ptr<const Equilibrium> equilibrium) { equilibrium_ = std::move(equilibrium); }
  const Equilibrium* equilibrium() const { return equilibrium_.get(); }
  const std::shared_ptr<const Equilibrium>& shared_equilibrium() const { return equilibrium_; }

  // The nodal-volume energy of nearly incompressible neo-Hookean objects (energy/nodal_volume.h),
  // part of the elastic group beside its blocks: Evaluate, the assembler and ForceResidual add
  // it. Not a block type: the Ceres back end refuses a problem with it. Null: none.
  void SetNodalVolume(std::shared_ptr<const NodalVolume> nodal) { nodal_volume_ = std::move(nodal); }
  const NodalVolume* nodal_volume() const { return nodal_volume_.get(); }

  // The energy at x by group, robust losses applied. Each set is summed in fixed chunks of
  // blocks, the chunks on up to `threads` threads (<= 0: ResolveThreadCount(0), as ParallelFor),
  // their sums added in chunk order: the same additions in the same order on any thread count.
  EnergyTerms Evaluate(const Vertices& x, int threads = 1) const;
  // A set's energy from its blocks' values (1/2 w rho - offset each, in block order, as a
  // linearization gives them), added as Evaluate adds them.
  static double SumBlockValues(const std::vector<double>& values);
  // The sum of the blocks' offsets (energy/term.h): a least-squares cost over the same
  // residuals is Evaluate's total plus this.
  double Offset() const;
  int num_blocks() const;

 private:
  template <class V, class F>
  static void VisitGroup(const V& sets, TermGroup group, F& f) {
    for (const auto& set : sets) {
      if (set.group() == group) f(set);
    }
  }
  int num_vertices_ = 0;
  Sets sets_;
  std::vector<char> fixed_;
  std::vector<std::array<int, 4>> coupling_;
  uint64_t coupling_revision_ = 0;
  std::shared_ptr<const Equilibrium> equilibrium_;
  std::shared_ptr<const NodalVolume> nodal_volume_;
};

}  // namespace energy
}  // namespace femreg

#endif  // FEMREG_ENERGY_PROBLEM_H_
