// The energy layer's per-element work on a box mesh of about `vertices` vertices (5:1:1, the
// demo beam's proportions), corotational elements with their rotations held at a bent shape
// (or, with neo_hookean:1, the stable neo-Hookean element at nu 0.45, as register takes it for
// nearly incompressible bodies) evaluated at a shape bent and twisted further, as inside a
// frame's solve:
//   AssembleExact      the exact Hessian and gradient (a physical-mode step's linearization);
//   ForceResidual      every vertex's force (a physical-mode line search's trial);
//   AssembleGaussNewton the classic step's system with the held rotations.
// Run single-threaded to compare the kernels:
//   bench/femreg_energy_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "energy/assembler.h"
#include "energy/elastic.h"
#include "energy/equilibrium.h"
#include "energy/problem.h"
#include "femreg/fem.h"
#include "femreg/io.h"
#include "femreg/mesh.h"

namespace {

struct Box {
  femreg::TetMesh mesh;
  femreg::ElasticModel model;
  femreg::energy::Problem problem;
  femreg::Vertices x;
};

// The held rotations at a bend of the beam's axis; x bent twice as far and twisted about the
// axis, so that each element's rotation is a few Newton steps from its held one.
std::unique_ptr<Box> BentBox(int vertices, bool neo_hookean = false) {
  auto box = std::make_unique<Box>();
  int n = 1;
  while ((5 * (n + 1) + 1) * (n + 2) * (n + 2) <= vertices) ++n;
  box->mesh = femreg::MakeBox(Eigen::Vector3d(0.5, 0.1, 0.1), 5 * n, n, n);
  femreg::Material material;
  material.youngs_modulus = 5e4;
  material.poisson_ratio = neo_hookean ? 0.45 : 0.35;
  box->model.Build(box->mesh, femreg::ElasticModelType::kCorotational, material);
  const int nv = box->mesh.num_vertices();
  auto bent = [&](double bend, double twist) {
    femreg::Vertices y = box->mesh.rest;
    for (int v = 0; v < nv; ++v) {
      const double s = y(v, 0) / 0.5, angle = twist * s;
      const double py = y(v, 1) - 0.05, pz = y(v, 2) - 0.05;
      y(v, 1) = 0.05 + std::cos(angle) * py - std::sin(angle) * pz;
      y(v, 2) = 0.05 + std::sin(angle) * py + std::cos(angle) * pz + bend * s * s;
    }
    return y;
  };
  box->model.UpdateRotations(bent(0.05, 0.0));
  box->x = bent(0.1, 0.2);
  femreg::energy::Problem& p = box->problem;
  p.Reset(nv);
  std::vector<std::array<int, 4>> cells;
  auto& elastic = p.AddSet<femreg::energy::ElasticElement>(femreg::energy::TermGroup::kElastic);
  auto& neo = p.AddSet<femreg::energy::NeoHookeanElement>(femreg::energy::TermGroup::kElastic);
  for (int e = 0; e < box->model.num_elements(); ++e) {
    femreg::energy::ElasticElement b;
    for (int k = 0; k < 4; ++k) b.vertices[k] = box->model.tets()(e, k);
    b.rest = &box->model.rest(e);
    b.rotation = &box->model.rotation(e);
    cells.push_back(b.vertices);
    if (!neo_hookean) {
      elastic.Add(b);
      continue;
    }
    femreg::energy::NeoHookeanElement n;
    n.vertices = b.vertices;
    n.rest = b.rest;
    neo.Add(n);
  }
  p.SetCoupling(cells);
  return box;
}

void Counters(benchmark::State& state, const Box& box) {
  state.counters["vertices"] = box.mesh.num_vertices();
  state.counters["tets"] = box.mesh.num_tets();
  state.counters["s_per_tet"] = benchmark::Counter(
      box.mesh.num_tets(), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void AssembleExact(benchmark::State& state) {
  const auto box = BentBox(static_cast<int>(state.range(0)), state.range(1) != 0);
  femreg::energy::Assembler assembler(1);
  assembler.Prepare(box->problem, box->x);
  Eigen::VectorXd g;
  for (auto _ : state) {
    assembler.AssembleSecondOrder(box->problem, box->x, femreg::energy::Curvature::kExact, true, &g);
    benchmark::DoNotOptimize(g.data());
  }
  Counters(state, *box);
}

void ForceResidual(benchmark::State& state) {
  const auto box = BentBox(static_cast<int>(state.range(0)), state.range(1) != 0);
  Eigen::VectorXd f;
  for (auto _ : state) {
    femreg::energy::ForceResidual(box->problem, box->x, &f);
    benchmark::DoNotOptimize(f.data());
  }
  Counters(state, *box);
}

void AssembleGaussNewton(benchmark::State& state) {
  const auto box = BentBox(static_cast<int>(state.range(0)));
  femreg::energy::Assembler assembler(1);
  assembler.Prepare(box->problem, box->x);
  Eigen::VectorXd g;
  for (auto _ : state) {
    assembler.AssembleGaussNewton(box->problem, box->x, true, &g);
    benchmark::DoNotOptimize(g.data());
  }
  Counters(state, *box);
}

void Sizes(benchmark::internal::Benchmark* b) {
  b->ArgName("vertices")->Arg(1000)->Arg(4000)->Unit(benchmark::kMillisecond);
}

void SizesAndElements(benchmark::internal::Benchmark* b) {
  b->ArgNames({"vertices", "neo_hookean"})->ArgsProduct({{1000, 4000}, {0, 1}})->Unit(benchmark::kMillisecond);
}

}  // namespace

BENCHMARK(AssembleExact)->Apply(SizesAndElements);
BENCHMARK(ForceResidual)->Apply(SizesAndElements);
BENCHMARK(AssembleGaussNewton)->Apply(Sizes);

BENCHMARK_MAIN();
