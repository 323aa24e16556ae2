#include "energy/problem.h"

#include <algorithm>
#include <atomic>

namespace femreg {
namespace energy {

uint64_t NextRevision() {
  static std::atomic<uint64_t> counter{0};
  return ++counter;
}

double& GroupEnergy(TermGroup group, EnergyTerms* terms) {
  switch (group) {
    case TermGroup::kElastic:
      return terms->elastic;
    case TermGroup::kTemporal:
      return terms->temporal;
    case TermGroup::kAnchor:
      return terms->anchor;
    case TermGroup::kData:
      return terms->data;
    case TermGroup::kLoad:
      return terms->load;
    case TermGroup::kCollision:
      break;
  }
  return terms->collision;
}

void Problem::Reset(int num_vertices) {
  num_vertices_ = num_vertices;
  std::apply([](auto&... vectors) { (vectors.clear(), ...); }, sets_);
  fixed_.clear();
}

void Problem::Clear(TermGroup group) {
  std::apply(
      [group](auto&... vectors) {
        auto erase = [group](auto& v) {
          v.erase(std::remove_if(v.begin(), v.end(), [group](const auto& s) { return s.group() == group; }),
                  v.end());
        };
        (erase(vectors), ...);
      },
      sets_);
}

void Problem::SetCoupling(std::vector<std::array<int, 4>> cells) {
  coupling_ = std::move(cells);
  coupling_revision_ = NextRevision();
}

EnergyTerms Problem::Evaluate(const Vertices& x) const {
  EnergyTerms terms;
  ForEachSet([&](const auto& set) { GroupEnergy(set.group(), &terms) += SetValue(set, x); });
  return terms;
}

double Problem::Offset() const {
  double total = 0.0;
  ForEachSet([&](const auto& set) {
    for (const auto& block : set.blocks()) total += OffsetValue(block, set.loss());
  });
  return total;
}

int Problem::num_blocks() const {
  int n = 0;
  ForEachSet([&](const auto& set) { n += set.size(); });
  return n;
}

}  // namespace energy
}  // namespace femreg
