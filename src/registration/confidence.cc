#include "registration/confidence.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {
namespace {

// A trusted frame's coverage enters the reference (a running mean over such frames).
constexpr double kTrusted = 0.5;
constexpr double kReferenceRate = 0.1;
// An object's volume may move this far (relative) from the trusted frames' before the frame
// is doubted: what a steady deformation changes between frames stays well within it.
constexpr double kVolumeTolerance = 0.02;
// The volume reference follows the trusted frames faster than the others: an object squeezed
// or stretched steadily stays within the tolerance of it.
constexpr double kVolumeRate = 0.3;
// The model->cloud pairs may fall to this share of the trusted frames' before the frame is
// doubted (a partial turn or a passing occluder takes less).
constexpr double kPairsShare = 0.6;
// The elements' strain the confidence reads: this quantile of their stretch deviations.
constexpr double kStrainQuantile = 0.95;

// The deformation gradient of object o's element e at its mesh.x.
Eigen::Matrix3d DeformationGradient(const ObjectState& o, int e) {
  const auto& t = o.model.tets();
  Eigen::Matrix3d Ds;
  const Eigen::Vector3d x0 = o.mesh.x.row(t(e, 0)).transpose();
  for (int k = 0; k < 3; ++k) Ds.col(k) = o.mesh.x.row(t(e, k + 1)).transpose() - x0;
  return Ds * o.model.rest(e).dm_inv;
}

int ModelPairs(const std::vector<DataPair>& pairs) {
  int n = 0;
  for (const DataPair& p : pairs) n += p.num_vertices == 1 ? 1 : 0;
  return n;
}

}  // namespace

double StretchDeviation(const Eigen::Matrix3d& F) {
  if (!(F.determinant() > 0.0)) return std::numeric_limits<double>::infinity();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(F.transpose() * F, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d l = eig.eigenvalues().cwiseMax(0.0);
  return std::max(std::sqrt(l(2)) - 1.0, 1.0 - std::sqrt(l(0)));
}

namespace {
// Widens the bounds on C's extreme eigenvalues below by this share of its largest reach: past the
// eigenvalues' round-off, which grows as the square root of the precision where two of them
// nearly coincide (about 1e-8 of the spread, found by a review over 4M matrices).
constexpr double kBoundSlack = 1e-6;

// lo <= StretchDeviation(F) <= hi without the eigenvalues of C = F^T F: its largest eigenvalue
// lies between its largest diagonal entry and the highest reach of Gershgorin's discs, its
// smallest between the lowest reach and the smallest diagonal entry.
void StretchDeviationBounds(const Eigen::Matrix3d& F, double* lo, double* hi) {
  if (!(F.determinant() > 0.0)) {
    *lo = *hi = std::numeric_limits<double>::infinity();
    return;
  }
  const Eigen::Matrix3d C = F.transpose() * F;
  double top = 0.0, bottom = std::numeric_limits<double>::infinity();
  double reach_top = 0.0, reach_bottom = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const double radius = std::abs(C(i, (i + 1) % 3)) + std::abs(C(i, (i + 2) % 3));
    top = std::max(top, C(i, i));
    bottom = std::min(bottom, C(i, i));
    reach_top = std::max(reach_top, C(i, i) + radius);
    reach_bottom = std::min(reach_bottom, C(i, i) - radius);
  }
  const double slack = kBoundSlack * std::max(1.0, reach_top);
  top -= slack;
  bottom += slack;
  reach_top += slack;
  reach_bottom -= slack;
  *lo = std::max(std::sqrt(std::max(top, 0.0)) - 1.0, 1.0 - std::sqrt(std::max(bottom, 0.0)));
  *hi = std::max(std::sqrt(reach_top) - 1.0, 1.0 - std::sqrt(std::max(reach_bottom, 0.0)));
}
}  // namespace

double StretchDeviationQuantile(int64_t n, double share, const std::function<Eigen::Matrix3d(int64_t)>& F,
                                int threads) {
  if (n <= 0) return 0.0;
  const size_t at = std::min(static_cast<size_t>(n) - 1, static_cast<size_t>(share * static_cast<double>(n)));
  std::vector<double> lo(static_cast<size_t>(n)), hi(static_cast<size_t>(n));
  // Each element on its own: the same on any thread count.
  ParallelFor(threads, n, 2048, [&](int64_t e) {
    StretchDeviationBounds(F(e), &lo[static_cast<size_t>(e)], &hi[static_cast<size_t>(e)]);
  });
  // The quantile is at least `floor`, the same rank among the lower bounds: an element whose
  // upper bound is below it ranks below the quantile, whatever its value. The others are
  // measured, and the quantile is their rank (at - below).
  std::vector<double> sorted = lo;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(at), sorted.end());
  const double floor = sorted[at];
  std::vector<int64_t> measured;
  for (int64_t e = 0; e < n; ++e) {
    if (!(hi[static_cast<size_t>(e)] < floor)) measured.push_back(e);
  }
  const size_t below = static_cast<size_t>(n) - measured.size();
  std::vector<double> deviation(measured.size());
  ParallelFor(threads, static_cast<int64_t>(measured.size()), 2048, [&](int64_t i) {
    deviation[static_cast<size_t>(i)] = StretchDeviation(F(measured[static_cast<size_t>(i)]));
  });
  const size_t rank = at - below;
  std::nth_element(deviation.begin(), deviation.begin() + static_cast<std::ptrdiff_t>(rank), deviation.end());
  return deviation[rank];
}

std::vector<double> VolumeRatios(const TrackerState& state) {
  std::vector<double> ratios;
  ratios.reserve(state.objects.size());
  std::vector<double> element;  // per element, summed in element order as on one thread
  for (const ObjectState& o : state.objects) {
    double volume = 0.0, rest = 0.0;
    const int ne = o.model.num_elements();
    element.resize(static_cast<size_t>(ne));
    ParallelFor(state.options.solver.num_threads, ne, 4096, [&](int64_t e) {
      element[static_cast<size_t>(e)] = DeformationGradient(o, static_cast<int>(e)).determinant();
    });
    for (int e = 0; e < ne; ++e) {
      volume += element[static_cast<size_t>(e)] * o.model.rest(e).volume;
      rest += o.model.rest(e).volume;
    }
    ratios.push_back(rest > 0.0 ? volume / rest : 1.0);
  }
  return ratios;
}

FrameConfidence MeasureConfidence(const TrackerState& state, const FrameCloud& fc,
                                  const std::vector<DataPair>& pairs, double tolerance,
                                  const DataSurface* surface, const SurfaceRings* rings) {
  FrameConfidence c;
  const Vertices& pair_x = surface != nullptr ? surface->view().x : state.x;
  // Fit: the cloud->model pairs (three vertices) within the tolerance at the result.
  double within = 0.0, all = 0.0;
  std::vector<std::pair<double, double>> distances;  // (distance, weight)
  for (const DataPair& p : pairs) {
    if (p.num_vertices != 3) continue;
    const double d = (p.Point(pair_x) - p.target).norm();
    all += p.weight;
    distances.emplace_back(d, p.weight);
    if (d <= tolerance) within += p.weight;
  }
  c.fit = all > 0.0 ? within / all : 0.0;
  // The residual over the better-fitting half of them (by weight): junk near the surface fills
  // the other half whether the fit is right or pulled; a pulled fit misses its own points too.
  std::sort(distances.begin(), distances.end());
  double half = 0.0, squares = 0.0;
  for (const auto& [d, weight] : distances) {
    if (half >= 0.5 * all) break;
    half += weight;
    squares += weight * d * d;
  }
  c.residual = half > 0.0 ? std::sqrt(squares / half) : 0.0;

  // Coverage: the surface vertices facing the sensor with a cloud point near.
  const TrackerState& covered_state = surface != nullptr ? surface->view() : state;
  const std::vector<int>& vertices = covered_state.surface_vertices;
  // Row i: vertices[i]'s normal (the same numbers either way).
  Eigen::MatrixXd normals;
  if (rings != nullptr && rings->num_vertices() == covered_state.x.rows()) {
    normals = VertexNormalsAt(covered_state.x, covered_state.surface, *rings, vertices);
  } else {
    const Eigen::MatrixXd all_normals = covered_state.VertexNormals();
    normals.resize(static_cast<Eigen::Index>(vertices.size()), 3);
    for (size_t i = 0; i < vertices.size(); ++i) normals.row(static_cast<Eigen::Index>(i)) = all_normals.row(vertices[i]);
  }
  // Whether vertices[i] has a cloud point within the tolerance: its object's residual, or on a
  // data surface a search bounded there (only the facing vertices are asked, and a vertex far
  // from the cloud costs little).
  auto is_covered = [&](size_t i) {
    const int v = vertices[i];
    if (surface != nullptr) return fc.index != nullptr && fc.index->AnyWithin(covered_state.x.row(v).transpose(), tolerance);
    const int o = state.vertex_object[static_cast<size_t>(v)];
    const double d = state.residuals[static_cast<size_t>(o)](v - state.objects[static_cast<size_t>(o)].offset);
    return std::isfinite(d) && d <= tolerance;
  };
  int facing = 0, covered = 0;
  for (size_t i = 0; i < vertices.size(); ++i) {
    const int v = vertices[i];
    if (!fc.Faces(covered_state.x.row(v).transpose(), normals.row(static_cast<Eigen::Index>(i)).transpose())) continue;
    ++facing;
    if (is_covered(i)) ++covered;
  }
  c.coverage = facing > 0 ? static_cast<double>(covered) / facing : 0.0;

  // Strain: the 95th percentile of the elements' stretch deviations.
  std::vector<int64_t> first_element;  // per object, its first element's number over all objects
  int64_t elements = 0;
  for (const ObjectState& o : state.objects) {
    first_element.push_back(elements);
    elements += o.model.num_elements();
  }
  if (elements > 0) {
    c.strain = StretchDeviationQuantile(elements, kStrainQuantile, [&](int64_t e) {
      const size_t o = static_cast<size_t>(std::upper_bound(first_element.begin(), first_element.end(), e) -
                                           first_element.begin()) - 1;
      return DeformationGradient(state.objects[o], static_cast<int>(e - first_element[o]));
    }, state.options.solver.num_threads);
  }
  const bool first = state.coverage_reference <= 0.0;  // the first solved frame sets the levels
  const double coverage_score = first ? 1.0 : std::min(1.0, c.coverage / state.coverage_reference);
  const double residual_score =
      first || c.residual <= 0.0 ? 1.0 : std::min(1.0, 2.0 * state.residual_reference / c.residual);
  const double s = c.strain;
  const double strain_score = std::isfinite(s) ? 1.0 / (1.0 + s * s * s * s) : 0.0;
  // Volume: the object that moved furthest from the volume its trusted frames kept.
  const std::vector<double> volumes = VolumeRatios(state);
  if (!first && state.volume_reference.size() == volumes.size()) {
    for (size_t o = 0; o < volumes.size(); ++o) {
      if (state.volume_reference[o] > 0.0) {
        const double change = std::abs(volumes[o] / state.volume_reference[o] - 1.0);
        c.volume_change = std::max(c.volume_change, change);
      }
    }
  }
  const double volume_score =
      c.volume_change > kVolumeTolerance ? kVolumeTolerance / c.volume_change : 1.0;
  // Pairs: how much of the surface facing the sensor the cloud pairs back, against the trusted
  // frames.
  double pairs_score = 1.0;
  if (!first && state.pairs_reference > 0.0) {
    const double share = ModelPairs(pairs) / (kPairsShare * state.pairs_reference);
    pairs_score = std::min(1.0, share * share);
  }
  c.confidence = c.fit * coverage_score * residual_score * strain_score * volume_score * pairs_score;
  return c;
}

void UpdateReferences(const FrameConfidence& confidence, const std::vector<DataPair>& pairs,
                      TrackerState* state) {
  const bool first = state->coverage_reference <= 0.0;
  if (!first && confidence.confidence < kTrusted) return;
  auto update = [first](double value, double* reference, double rate = kReferenceRate) {
    *reference = first ? value : (1.0 - rate) * *reference + rate * value;
  };
  update(std::max(confidence.coverage, 1e-3), &state->coverage_reference);
  update(confidence.residual, &state->residual_reference);
  update(ModelPairs(pairs), &state->pairs_reference);
  const std::vector<double> volumes = VolumeRatios(*state);
  if (first || state->volume_reference.size() != volumes.size()) {
    state->volume_reference = volumes;  // the first frame, or an object count that changed
  } else {
    for (size_t o = 0; o < volumes.size(); ++o) {
      update(volumes[o], &state->volume_reference[o], kVolumeRate);
    }
  }
}

}  // namespace femreg
