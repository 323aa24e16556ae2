// The physical mode's preconditioner where the data hold soft modes of K
// (solvers/fast/equilibrium_step.h, docs/theory/equilibrium.md#solving-it): a factor of
// K + s H instead of K. Along a soft mode of K that the data hold, (K + s H) Phi (K + s H)
// ~ s^2 H Phi H, which is H for s = (phi h)^-1/2, phi the free surface's force weight and h
// the data's stiffness per coordinate; along a stiff one K dominates as before.
#ifndef FEMREG_SOLVERS_FAST_DATA_SHIFT_H_
#define FEMREG_SOLVERS_FAST_DATA_SHIFT_H_

#include <Eigen/SparseCore>
#include <vector>

#include "energy/problem.h"

namespace femreg {
namespace fast_backend {

// Adds s H to *K where K's pattern has H's entries (it is a preconditioner: the others are left
// out), not in a fixed vertex's rows or columns, and returns K's values before. H is the
// objective's Gauss-Newton matrix: the data, and the temporal springs, soft anchors and the
// inversion barrier where they act. phi is the mean force weight of the free-surface vertices
// (problem.equilibrium()), h the mean diagonal of H over the coordinates where it is at least
// 1 % of its largest: the observed vertices and the anchored ones, not the temporal springs.
// Returns nothing (and adds nothing) without a free vertex or such a coordinate.
std::vector<double> AddDataShift(const energy::Problem& problem, const Eigen::SparseMatrix<double>& H,
                                 Eigen::SparseMatrix<double>* K);

}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_DATA_SHIFT_H_
