#include "energy/problem.h"

#include <algorithm>
#include <atomic>
#include <vector>

#include "energy/nodal_volume.h"
#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {
namespace energy {

uint64_t NextRevision() {
  static std::atomic<uint64_t> counter{0};
  return ++counter;
}

double& GroupEnergy(TermGroup group, EnergyTerms* terms) {
  switch (group) {
    case TermGroup::kElastic:
    case TermGroup::kBarrier:
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
  equilibrium_.reset();
  nodal_volume_.reset();
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
  if (group == TermGroup::kElastic) nodal_volume_.reset();
}

void Problem::SetCoupling(std::vector<std::array<int, 4>> cells) {
  coupling_ = std::move(cells);
  coupling_revision_ = NextRevision();
}

namespace {

// Blocks per chunk of a set's sum: a chunk's work well above a team's start
// (docs/notes/2026-11-28-figures-from-code-comments.md). Each chunk is summed in block order, the
// chunks' sums in chunk order.
constexpr int kChunk = 256;

// The values of a set's blocks at x, in chunks on up to `threads` threads.
template <class T>
void BlockValues(const TermSet<T>& set, const Vertices& x, int threads, std::vector<double>* values) {
  const int size = set.size();
  const int chunks = (size + kChunk - 1) / kChunk;
  values->resize(static_cast<size_t>(size));
  const std::vector<T>& blocks = set.blocks();
  auto chunk = [&](int c) {
    const int end = std::min(size, (c + 1) * kChunk);
    for (int b = c * kChunk; b < end; ++b) {
      (*values)[static_cast<size_t>(b)] = BlockValue(blocks[static_cast<size_t>(b)], set.loss(), x);
    }
  };
  const int team = PhaseThreads(ResolveThreadCount(threads), chunks, 2);  // 2 chunks a thread at least
  if (team > 1) {
    RunTasks(team, chunks, chunk);
  } else {
    for (int c = 0; c < chunks; ++c) chunk(c);
  }
}

}  // namespace

double Problem::SumBlockValues(const std::vector<double>& values) {
  const size_t size = values.size();
  double total = 0.0;
  for (size_t begin = 0; begin < size; begin += kChunk) {
    const size_t end = std::min(size, begin + kChunk);
    double sum = 0.0;
    for (size_t b = begin; b < end; ++b) sum += values[b];
    total += sum;
  }
  return total;
}

EnergyTerms Problem::Evaluate(const Vertices& x, int threads) const {
  EnergyTerms terms;
  std::vector<double> values;
  const uint32_t minimized = equilibrium_ ? ObjectiveGroups() : ~0u;
  ForEachSet([&](const auto& set) {
    if (!InGroups(minimized, set.group())) return;
    BlockValues(set, x, threads, &values);
    GroupEnergy(set.group(), &terms) += SumBlockValues(values);
  });
  if (nodal_volume_ && InGroups(minimized, TermGroup::kElastic)) terms.elastic += nodal_volume_->Evaluate(x, nullptr);
  if (equilibrium_) {
    Eigen::VectorXd f;
    ForceResidual(*this, x, &f);
    terms.equilibrium = EquilibriumEnergy(*equilibrium_, f);
  }
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
