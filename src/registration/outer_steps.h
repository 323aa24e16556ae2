// Steps over the outer iterations (solver.outer_steps; docs/notes/2026-11-30-outer-steps.md):
// an outer iteration is a map x -> G(x), the solve from x with the rotations, pairs and
// contacts found at x. Anderson's method combines its last iterations into a point further on,
// which the tracker keeps only where the energy with everything found there is lower.
#ifndef FEMREG_REGISTRATION_OUTER_STEPS_H_
#define FEMREG_REGISTRATION_OUTER_STEPS_H_

#include <functional>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {

class OuterStepHistory {
 public:
  // depth: the differences of past iterations a step combines (>= 1).
  explicit OuterStepHistory(int depth = 2) : depth_(depth) {}
  void Clear() {
    results_.clear();
    moves_.clear();
  }
  // Outer iteration k's solve went from `start` to `reached` (G(start)). A k that does not
  // follow the last one recorded, or other rows, starts the history again.
  void Record(int k, const Vertices& start, const Vertices& reached);
  int size() const { return static_cast<int>(moves_.size()); }
  // Anderson's point G(x_k) - dG gamma, with gamma minimising |f_k - dF gamma| over the moves
  // f = G(x) - x and dF, dG the differences of the last iterations' moves and results. False
  // with fewer than two iterations recorded, moves that do not differ, or a result that is
  // not finite.
  bool Propose(Vertices* further) const;

 private:
  int depth_;
  int last_k_ = -1;
  std::vector<Vertices> results_, moves_;  // oldest first, at most depth_ + 1
};

// The energies a step was judged by, and whether it was kept.
struct OuterStepTrial {
  double at = 0.0;       // at the solve's end
  double further = 0.0;  // at the step's end (not evaluated: infinity)
  bool kept = false;
};

// energy(y): everything found at y (rotations, pairs, contacts) and the energy there. The step
// to `further` is kept where its energy is lower than at `reached`; not evaluated where
// reached's is not finite. The caller goes on from `further` if kept, else from `reached`
// (energy was last called at `further` if evaluated).
OuterStepTrial TryOuterStep(const Vertices& reached, const Vertices& further,
                            const std::function<double(const Vertices&)>& energy);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_OUTER_STEPS_H_
