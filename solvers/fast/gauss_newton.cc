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
  for (const ContactTerm& c : problem.contacts) {
    const double delta = c.Penetration(x);
    if (delta > 0) t.collision += 0.5 * problem.contact_stiffness * delta * delta;
  }
  return t;
}

struct Solver::Impl {
  int num_vertices = 0;
  std::vector<std::array<int, 4>> tets;          // the pattern's tetrahedra
  std::vector<std::pair<int, int>> extra_pairs;  // and contact couplings (a < b)
  void BuildPattern();
  Eigen::SparseMatrix<double> H;  // 3n by 3n, full 3x3 blocks for every vertex pair of a tet
  std::unordered_map<uint64_t, std::array<int, 3>> block_offsets;  // (a, b) -> column starts
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> cholesky;
  bool analysed = false;
  // Per elastic term (in the problem's order), the value offsets of its 16 blocks: found
  // once per pattern instead of hashed per assembly.
  std::vector<std::array<std::array<int, 3>, 16>> elastic_offsets;
  const std::array<int, 3>* Offsets(int a, int b) const {
    const auto it = block_offsets.find(Key(a, b));
    return it == block_offsets.end() ? nullptr : &it->second;
  }
  void AddAt(const std::array<int, 3>& offsets, const Eigen::Matrix3d& M) {
    double* v = H.valuePtr();
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 3; ++i) v[offsets[j] + i] += M(i, j);
    }
  }

  static uint64_t Key(int a, int b) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
  }
  // Adds the 3x3 block M to H at (a, b).
  void AddBlock(int a, int b, const Eigen::Matrix3d& M) {
    const std::array<int, 3>* offsets = Offsets(a, b);
    if (offsets != nullptr) AddAt(*offsets, M);  // outside the pattern: ignored
  }
  // H's elastic part: constant within one Solve (rotations fixed), assembled once.
  std::vector<double> elastic_values;
  bool elastic_valid = false;
  void Assemble(const Problem& problem, const Vertices& x, Eigen::VectorXd* g);
};

Solver::Solver() : impl_(new Impl) {}
Solver::~Solver() = default;

void Solver::SetPattern(int num_vertices, const std::vector<std::array<int, 4>>& tets) {
  Impl& m = *impl_;
  m.num_vertices = num_vertices;
  m.tets = tets;
  m.extra_pairs.clear();
  m.BuildPattern();
}

void Solver::Impl::BuildPattern() {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(tets.size() * 144 + 9 * static_cast<size_t>(num_vertices) + 18 * extra_pairs.size());
  auto add = [&](int a, int b) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) triplets.emplace_back(3 * a + i, 3 * b + j, 0.0);
  };
  for (int v = 0; v < num_vertices; ++v) add(v, v);
  for (const auto& t : tets) {
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) add(t[a], t[b]);
  }
  for (const auto& p : extra_pairs) {
    add(p.first, p.second);
    add(p.second, p.first);
  }
  H.resize(3 * num_vertices, 3 * num_vertices);
  H.setFromTriplets(triplets.begin(), triplets.end());
  H.makeCompressed();
  block_offsets.clear();
  const int* outer = H.outerIndexPtr();
  const int* inner = H.innerIndexPtr();
  for (int col = 0; col < H.cols(); col += 3) {
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
      block_offsets[Key(a, b)] = offsets;
    }
  }
  analysed = false;
  elastic_offsets.clear();
  elastic_valid = false;
}

void Solver::Impl::Assemble(const Problem& problem, const Vertices& x, Eigen::VectorXd* g) {
  if (elastic_valid) {
    std::copy(elastic_values.begin(), elastic_values.end(), H.valuePtr());
  } else {
    std::fill(H.valuePtr(), H.valuePtr() + H.nonZeros(), 0.0);
  }
  g->setZero(3 * num_vertices);
  if (elastic_offsets.size() != problem.elastic.size()) {
    elastic_offsets.resize(problem.elastic.size());
    for (size_t t = 0; t < problem.elastic.size(); ++t) {
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
          const std::array<int, 3>* o = Offsets(problem.elastic[t].vertices[a], problem.elastic[t].vertices[b]);
          elastic_offsets[t][4 * a + b] = o ? *o : std::array<int, 3>{-1, -1, -1};
        }
      }
    }
  }
  for (size_t t = 0; t < problem.elastic.size(); ++t) {
    const ElasticTerm& e = problem.elastic[t];
    const Eigen::Matrix3d& R = *e.rotation;
    const Vector12 xe = Gather(e, x);
    Vector12 u;
    for (int k = 0; k < 4; ++k) u.segment<3>(3 * k) = R.transpose() * xe.segment<3>(3 * k) - e.rest->X.segment<3>(3 * k);
    const Vector12 ku = e.rest->K * u;
    for (int a = 0; a < 4; ++a) {
      g->segment<3>(3 * e.vertices[a]) += e.weight * R * ku.segment<3>(3 * a);
      if (elastic_valid) continue;
      for (int b = 0; b < 4; ++b) {
        const std::array<int, 3>& o = elastic_offsets[t][4 * a + b];
        if (o[0] >= 0) AddAt(o, e.weight * R * e.rest->K.block<3, 3>(3 * a, 3 * b) * R.transpose());
      }
    }
  }
  if (!elastic_valid) {
    elastic_values.assign(H.valuePtr(), H.valuePtr() + H.nonZeros());
    elastic_valid = true;
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
  // Contacts active at x: gradient -k delta w_i n, Hessian k w_i w_j n n^T (exact while the
  // active set holds; the energy check of the step sees the ones a step activates).
  const double k = problem.contact_stiffness;
  for (const ContactTerm& c : problem.contacts) {
    const double delta = c.Penetration(x);
    if (!(delta > 0)) continue;
    const Eigen::Matrix3d nn = k * c.normal * c.normal.transpose();
    for (int i = 0; i < c.num_vertices; ++i) {
      if (c.weights[i] == 0.0) continue;
      g->segment<3>(3 * c.vertices[i]) -= k * delta * c.weights[i] * c.normal;
      for (int j = 0; j < c.num_vertices; ++j) {
        if (c.weights[j] != 0.0) AddBlock(c.vertices[i], c.vertices[j], c.weights[i] * c.weights[j] * nn);
      }
    }
  }
}

SolveSummary Solver::Solve(const Problem& problem, int max_iterations, Vertices* x,
                          double relative_tolerance) {
  Impl& m = *impl_;
  SolveSummary summary;
  if (x->rows() != m.num_vertices) {
    summary.success = false;
    summary.message = "fast back end: the pattern was set for another vertex count";
    return summary;
  }
  // Contacts coupling vertices outside the pattern widen it (and redo the analysis).
  {
    std::vector<std::pair<int, int>> missing;
    for (const ContactTerm& c : problem.contacts)
      for (int i = 0; i < c.num_vertices; ++i)
        for (int j = i + 1; j < c.num_vertices; ++j) {
          const int a = std::min(c.vertices[i], c.vertices[j]), b = std::max(c.vertices[i], c.vertices[j]);
          if (a != b && c.weights[i] != 0.0 && c.weights[j] != 0.0 && m.Offsets(a, b) == nullptr) {
            missing.emplace_back(a, b);
          }
        }
    if (!missing.empty()) {
      std::sort(missing.begin(), missing.end());
      missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
      m.extra_pairs.insert(m.extra_pairs.end(), missing.begin(), missing.end());
      m.BuildPattern();
      ++summary.pattern_rebuilds;
    }
  }
  const bool any_fixed = !problem.fixed.empty();
  const int n = static_cast<int>(m.H.cols());
  const int* outer = m.H.outerIndexPtr();
  const int* inner = m.H.innerIndexPtr();
  // Where each column's diagonal entry sits.
  std::vector<int> diagonal_at(static_cast<size_t>(n), -1);
  for (int c = 0; c < n; ++c) {
    for (int p = outer[c]; p < outer[c + 1]; ++p) {
      if (inner[p] == c) diagonal_at[static_cast<size_t>(c)] = p;
    }
  }
  m.elastic_valid = false;  // rotations may have changed since the last Solve
  double energy = Evaluate(problem, *x).total();
  double lambda = 1e-8;
  double first_gradient = -1.0;
  Eigen::VectorXd g;
  std::vector<double> diagonal(static_cast<size_t>(n));
  int steps = 0;
  while (steps < max_iterations) {
    m.Assemble(problem, *x, &g);
    double* values = m.H.valuePtr();
    if (any_fixed) {  // identity rows and columns, no step
      for (int c = 0; c < n; ++c) {
        const bool col_fixed = problem.fixed[static_cast<size_t>(c / 3)];
        for (int p = outer[c]; p < outer[c + 1]; ++p) {
          if (col_fixed || problem.fixed[static_cast<size_t>(inner[p] / 3)]) {
            values[p] = (inner[p] == c) ? 1.0 : 0.0;
          }
        }
        if (col_fixed) g[c] = 0.0;
      }
    }
    // Converged when the gradient has fallen far below where it started: with rotations and
    // pairs fixed the problem is quadratic but for the robust weights, so this usually
    // holds right after the first step, without another factorization.
    const double gradient = g.lpNorm<Eigen::Infinity>();
    if (first_gradient < 0) first_gradient = gradient;
    if (gradient <= 1e-9 * first_gradient || gradient == 0.0) {
      summary.iterations = steps;
      return summary;
    }
    double max_diagonal = 0.0;
    for (int c = 0; c < n; ++c) {
      diagonal[static_cast<size_t>(c)] = values[diagonal_at[static_cast<size_t>(c)]];
      max_diagonal = std::max(max_diagonal, diagonal[static_cast<size_t>(c)]);
    }
    bool accepted = false;
    while (!accepted && steps < max_iterations) {
      // Marquardt damping on the diagonal (and a whisper of Tikhonov for unreferenced dofs).
      for (int c = 0; c < n; ++c) {
        values[diagonal_at[static_cast<size_t>(c)]] = diagonal[static_cast<size_t>(c)] * (1.0 + lambda) + 1e-12 * max_diagonal;
      }
      if (!m.analysed) {
        m.cholesky.analyzePattern(m.H);
        m.analysed = true;
      }
      m.cholesky.factorize(m.H);
      ++summary.factorizations;
      ++steps;
      if (m.cholesky.info() != Eigen::Success) {
        lambda = std::max(lambda * 100.0, 1e-6);
        continue;
      }
      const Eigen::VectorXd dx = m.cholesky.solve(-g);
      Vertices trial = *x;
      for (int v = 0; v < m.num_vertices; ++v) trial.row(v) += dx.segment<3>(3 * v).transpose();
      const double trial_energy = Evaluate(problem, trial).total();
      if (std::isfinite(trial_energy) && trial_energy <= energy) {
        const double change = (energy - trial_energy) / std::max(energy, 1e-300);
        *x = trial;
        energy = trial_energy;
        lambda = std::max(lambda * 0.1, 1e-12);
        accepted = true;
        if (change < relative_tolerance || dx.lpNorm<Eigen::Infinity>() < 1e-14) {
          summary.iterations = steps;
          return summary;
        }
      } else {
        lambda = std::max(lambda * 10.0, 1e-6);
      }
    }
    if (!accepted) break;
  }
  summary.iterations = steps;
  return summary;
}

}  // namespace fast_backend
}  // namespace femreg
