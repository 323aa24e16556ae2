#include "solvers/fast/closing_contacts.h"

#include <algorithm>
#include <type_traits>

#include "energy/contact.h"
#include "energy/equilibrium.h"

namespace femreg {
namespace fast_backend {

namespace {

template <typename T>
struct IsContactPenalty : std::false_type {};
template <int N>
struct IsContactPenalty<energy::ContactPenalty<N>> : std::true_type {};

}  // namespace

int ClosingContacts::Find(const energy::Problem& problem, const Vertices& x, const Eigen::VectorXd& dx,
                          bool add) {
  if (!add) Clear();
  const size_t before_count = closing_.size();
  int set_index = -1;
  problem.ForEachSet([&](const auto& set) {
    using T = typename std::decay_t<decltype(set)>::Block;
    ++set_index;
    if constexpr (IsContactPenalty<T>::value) {
      static_assert(T::kVertices <= 6, "a contact stencil has at most six vertices");
      // As the potential's assembly takes them: its groups, no robust loss.
      if (!energy::InGroups(energy::PhysicsGroups(), set.group()) || set.loss().robust()) return;
      int block_index = -1;
      for (const T& b : set.blocks()) {
        ++block_index;
        if (!(b.weight > 0.0)) continue;
        std::array<const double*, T::kVertices> at;
        for (int i = 0; i < T::kVertices; ++i) at[i] = x.row(b.vertices[i]).data();
        const double before = b.Penetration(at.data());
        double after = before;
        for (int i = 0; i < T::kVertices; ++i) {
          after -= b.coefficients[i] * b.normal.dot(dx.segment<3>(3 * b.vertices[i]));
        }
        if (before > 0.0 || after <= 0.0) continue;
        const std::pair<int, int> key(set_index, block_index);
        if (add && std::find(keys_.begin(), keys_.end(), key) != keys_.end()) continue;
        Closing c;
        for (int i = 0; i < T::kVertices; ++i) {
          if (problem.is_fixed(b.vertices[i])) continue;
          c.vertices[c.count] = b.vertices[i];
          c.coefficients[c.count] = b.coefficients[i];
          ++c.count;
        }
        c.normal = b.normal;
        c.stiffness = b.weight;
        c.delta = before;
        if (c.count > 0) {
          closing_.push_back(c);
          keys_.push_back(key);
        }
      }
    }
  });
  return static_cast<int>(closing_.size() - before_count);
}

void ClosingContacts::AddForce(Eigen::VectorXd* f) const {
  for (const Closing& c : closing_) {
    for (int i = 0; i < c.count; ++i) {
      f->segment<3>(3 * c.vertices[i]) -= c.stiffness * c.delta * c.coefficients[i] * c.normal;
    }
  }
}

void ClosingContacts::AddProduct(const Eigen::VectorXd& p, Eigen::VectorXd* y) const {
  for (const Closing& c : closing_) {
    double along = 0.0;
    for (int i = 0; i < c.count; ++i) along += c.coefficients[i] * c.normal.dot(p.segment<3>(3 * c.vertices[i]));
    for (int i = 0; i < c.count; ++i) {
      y->segment<3>(3 * c.vertices[i]) += c.stiffness * c.coefficients[i] * along * c.normal;
    }
  }
}

}  // namespace fast_backend
}  // namespace femreg
