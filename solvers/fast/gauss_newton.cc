#include "solvers/fast/gauss_newton.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>

namespace femreg {
namespace fast_backend {

namespace {

// The loss of Ceres' HuberLoss, CauchyLoss and TukeyLoss on the squared norm s: rho(s) and
// rho'(s).
void Loss(RobustLoss loss, double a, double s, double* rho, double* rho1) {
  const double a2 = a * a;
  switch (loss) {
    case RobustLoss::kNone:
      *rho = s;
      *rho1 = 1.0;
      return;
    case RobustLoss::kHuber:
      if (s <= a2) {
        *rho = s;
        *rho1 = 1.0;
      } else {
        const double r = std::sqrt(s);
        *rho = 2.0 * a * r - a2;
        *rho1 = a / r;
      }
      return;
    case RobustLoss::kCauchy:
      *rho = a2 * std::log1p(s / a2);
      *rho1 = 1.0 / (1.0 + s / a2);
      return;
    case RobustLoss::kTukey:
      if (s <= a2) {
        const double t = 1.0 - s / a2;
        *rho = a2 / 3.0 * (1.0 - t * t * t);
        *rho1 = t * t;
      } else {
        *rho = a2 / 3.0;
        *rho1 = 0.0;
      }
      return;
  }
}

Eigen::Vector3d PointOf(const PointTerm& p, const Vertices& x) {
  Eigen::Vector3d q = Eigen::Vector3d::Zero();
  for (int k = 0; k < p.num_vertices; ++k) q += p.barycentric[k] * x.row(p.vertices[k]).transpose();
  return q;
}

// Squared norm of a data residual.
double DataSquaredNorm(const PointTerm& p, const Vertices& x) {
  const Eigen::Vector3d d = PointOf(p, x) - p.target;
  if (p.normal.squaredNorm() > 0) {
    const double r = p.normal.dot(d);
    return r * r;
  }
  return d.squaredNorm();
}

Vector12 Gather(const ElasticTerm& e, const Vertices& x) {
  Vector12 xe;
  for (int k = 0; k < 4; ++k) xe.segment<3>(3 * k) = x.row(e.vertices[k]).transpose();
  return xe;
}

}  // namespace

EnergyTerms Evaluate(const Problem& problem, const Vertices& x) {
  EnergyTerms t;
  for (const ElasticTerm& e : problem.elastic) {
    t.elastic += e.weight * ElementEnergy(*e.rest, *e.rotation, Gather(e, x));
  }
  for (const EdgeSpringTerm& s : problem.edges) {
    const double stretch = (x.row(s.a) - x.row(s.b)).norm() - s.length;
    t.elastic += 0.5 * s.stiffness * stretch * stretch;
  }
  for (const PointTerm& p : problem.data) {
    double rho, rho1;
    Loss(problem.loss, problem.loss_scale, DataSquaredNorm(p, x), &rho, &rho1);
    t.data += 0.5 * problem.data_weight * rho;
  }
  for (const SpringTerm& s : problem.temporal) {
    t.temporal += 0.5 * s.weight * (x.row(s.vertex).transpose() - s.target).squaredNorm();
  }
  for (const SpringTerm& s : problem.anchors) {
    t.anchor += 0.5 * s.weight * (x.row(s.vertex).transpose() - s.target).squaredNorm();
  }
  return t;
}

struct Solver::Impl {
  int num_vertices = 0;
  Eigen::SparseMatrix<double> H;  // 3n by 3n, full 3x3 blocks for every vertex pair of a tet
  std::unordered_map<uint64_t, std::array<int, 3>> block_offsets;  // (a, b) -> column starts
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> cholesky;
  bool analysed = false;

  static uint64_t Key(int a, int b) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
  }
  // Adds the 3x3 block M to H at (a, b).
  void AddBlock(int a, int b, const Eigen::Matrix3d& M) {
    const auto it = block_offsets.find(Key(a, b));
    if (it == block_offsets.end()) return;  // outside the pattern: programmer error, ignored
    double* v = H.valuePtr();
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 3; ++i) v[it->second[j] + i] += M(i, j);
    }
  }
  void Assemble(const Problem& problem, const Vertices& x, Eigen::VectorXd* g);
};

Solver::Solver() : impl_(new Impl) {}
Solver::~Solver() = default;

void Solver::SetPattern(int num_vertices, const std::vector<std::array<int, 4>>& tets) {
  Impl& m = *impl_;
  m.num_vertices = num_vertices;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(tets.size() * 144 + 9 * static_cast<size_t>(num_vertices));
  auto add = [&](int a, int b) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) triplets.emplace_back(3 * a + i, 3 * b + j, 0.0);
  };
  for (int v = 0; v < num_vertices; ++v) add(v, v);
  for (const auto& t : tets) {
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) add(t[a], t[b]);
  }
  m.H.resize(3 * num_vertices, 3 * num_vertices);
  m.H.setFromTriplets(triplets.begin(), triplets.end());
  m.H.makeCompressed();
  m.block_offsets.clear();
  const int* outer = m.H.outerIndexPtr();
  const int* inner = m.H.innerIndexPtr();
  for (int col = 0; col < m.H.cols(); col += 3) {
    const int b = col / 3;
    for (int p = outer[col]; p < outer[col + 1]; p += 3) {
      const int a = inner[p] / 3;
      std::array<int, 3> offsets;
      for (int j = 0; j < 3; ++j) {
        // Rows 3a..3a+2 sit together in each of the block's three columns.
        const int* begin = inner + outer[col + j];
        const int* end = inner + outer[col + j + 1];
        offsets[j] = static_cast<int>(std::lower_bound(begin, end, 3 * a) - inner);
      }
      m.block_offsets[Impl::Key(a, b)] = offsets;
    }
  }
  m.analysed = false;
}

void Solver::Impl::Assemble(const Problem& problem, const Vertices& x, Eigen::VectorXd* g) {
  std::fill(H.valuePtr(), H.valuePtr() + H.nonZeros(), 0.0);
  g->setZero(3 * num_vertices);
  for (const ElasticTerm& e : problem.elastic) {
    const Eigen::Matrix3d& R = *e.rotation;
    const Vector12 xe = Gather(e, x);
    Vector12 u;
    for (int k = 0; k < 4; ++k) u.segment<3>(3 * k) = R.transpose() * xe.segment<3>(3 * k) - e.rest->X.segment<3>(3 * k);
    const Vector12 ku = e.rest->K * u;
    for (int a = 0; a < 4; ++a) {
      g->segment<3>(3 * e.vertices[a]) += e.weight * R * ku.segment<3>(3 * a);
      for (int b = 0; b < 4; ++b) {
        AddBlock(e.vertices[a], e.vertices[b],
                 e.weight * R * e.rest->K.block<3, 3>(3 * a, 3 * b) * R.transpose());
      }
    }
  }
  for (const EdgeSpringTerm& s : problem.edges) {
    const Eigen::Vector3d d = x.row(s.a) - x.row(s.b);
    const double len = d.norm();
    if (!(len > 0)) continue;
    const Eigen::Vector3d u = d / len;
    const Eigen::Matrix3d K = s.stiffness * u * u.transpose();
    const Eigen::Vector3d f = s.stiffness * (len - s.length) * u;
    g->segment<3>(3 * s.a) += f;
    g->segment<3>(3 * s.b) -= f;
    AddBlock(s.a, s.a, K);
    AddBlock(s.b, s.b, K);
    AddBlock(s.a, s.b, -K);
    AddBlock(s.b, s.a, -K);
  }
  for (const PointTerm& p : problem.data) {
    const Eigen::Vector3d d = PointOf(p, x) - p.target;
    const bool plane = p.normal.squaredNorm() > 0;
    const double r_plane = plane ? p.normal.dot(d) : 0.0;
    const double s = plane ? r_plane * r_plane : d.squaredNorm();
    double rho, rho1;
    Loss(problem.loss, problem.loss_scale, s, &rho, &rho1);
    const double w = problem.data_weight * rho1;
    if (w == 0.0) continue;
    const Eigen::Matrix3d N = plane ? Eigen::Matrix3d(p.normal * p.normal.transpose())
                                    : Eigen::Matrix3d::Identity();
    const Eigen::Vector3d r = plane ? Eigen::Vector3d(r_plane * p.normal) : d;
    for (int i = 0; i < p.num_vertices; ++i) {
      g->segment<3>(3 * p.vertices[i]) += w * p.barycentric[i] * r;
      for (int j = 0; j < p.num_vertices; ++j) {
        AddBlock(p.vertices[i], p.vertices[j], w * p.barycentric[i] * p.barycentric[j] * N);
      }
    }
  }
  for (const auto* springs : {&problem.temporal, &problem.anchors}) {
    for (const SpringTerm& s : *springs) {
      g->segment<3>(3 * s.vertex) += s.weight * (x.row(s.vertex).transpose() - s.target);
      AddBlock(s.vertex, s.vertex, s.weight * Eigen::Matrix3d::Identity());
    }
  }
}

SolveSummary Solver::Solve(const Problem& problem, int max_iterations, Vertices* x) {
  Impl& m = *impl_;
  SolveSummary summary;
  if (x->rows() != m.num_vertices) {
    summary.success = false;
    summary.message = "fast back end: the pattern was set for another vertex count";
    return summary;
  }
  const bool any_fixed = !problem.fixed.empty();
  double energy = Evaluate(problem, *x).total();
  double lambda = 1e-8;
  Eigen::VectorXd g;
  for (int it = 0; it < max_iterations; ++it) {
    m.Assemble(problem, *x, &g);
    // Marquardt damping on the diagonal; hard-fixed vertices get identity rows and no step.
    double* values = m.H.valuePtr();
    const int* outer = m.H.outerIndexPtr();
    const int* inner = m.H.innerIndexPtr();
    std::vector<double> diagonal(static_cast<size_t>(m.H.cols()));
    double max_diagonal = 0.0;
    for (int c = 0; c < m.H.cols(); ++c) {
      for (int p = outer[c]; p < outer[c + 1]; ++p) {
        if (inner[p] == c) diagonal[static_cast<size_t>(c)] = values[p];
      }
      max_diagonal = std::max(max_diagonal, diagonal[static_cast<size_t>(c)]);
    }
    if (any_fixed) {
      for (int c = 0; c < m.H.cols(); ++c) {
        const bool col_fixed = problem.fixed[static_cast<size_t>(c / 3)];
        for (int p = outer[c]; p < outer[c + 1]; ++p) {
          const bool row_fixed = problem.fixed[static_cast<size_t>(inner[p] / 3)];
          if (col_fixed || row_fixed) values[p] = (inner[p] == c) ? 1.0 : 0.0;
        }
        if (col_fixed) {
          g[c] = 0.0;
          diagonal[static_cast<size_t>(c)] = 1.0;
        }
      }
    }
    const Eigen::SparseMatrix<double> H0 = m.H;
    bool accepted = false;
    while (!accepted && it < max_iterations) {
      m.H = H0;
      values = m.H.valuePtr();
      for (int c = 0; c < m.H.cols(); ++c) {
        for (int p = outer[c]; p < outer[c + 1]; ++p) {
          if (inner[p] == c) values[p] += lambda * diagonal[static_cast<size_t>(c)] + 1e-12 * max_diagonal;
        }
      }
      if (!m.analysed) {
        m.cholesky.analyzePattern(m.H);
        m.analysed = true;
      }
      m.cholesky.factorize(m.H);
      ++summary.factorizations;
      if (m.cholesky.info() != Eigen::Success) {
        lambda = std::max(lambda * 100.0, 1e-6);
        ++it;
        if (lambda > 1e8) break;
        continue;
      }
      const Eigen::VectorXd dx = m.cholesky.solve(-g);
      Vertices trial = *x;
      for (int v = 0; v < m.num_vertices; ++v) trial.row(v) += dx.segment<3>(3 * v).transpose();
      const double trial_energy = Evaluate(problem, trial).total();
      ++summary.iterations;
      if (std::isfinite(trial_energy) && trial_energy <= energy) {
        const double change = (energy - trial_energy) / std::max(energy, 1e-300);
        *x = trial;
        energy = trial_energy;
        lambda = std::max(lambda * 0.1, 1e-12);
        accepted = true;
        if (change < 1e-10 || dx.lpNorm<Eigen::Infinity>() < 1e-12) return summary;
      } else {
        lambda = std::max(lambda * 10.0, 1e-6);
        ++it;
        if (lambda > 1e8) break;
      }
    }
    if (!accepted) break;
  }
  m.H.makeCompressed();
  return summary;
}

}  // namespace fast_backend
}  // namespace femreg
