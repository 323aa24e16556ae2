#include "registration/pose_verifier.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "parallel/pool.h"

namespace femreg {

namespace {
constexpr double kKeep = 0.8;  // the trimmed fit keeps the closest 80 % of the points
constexpr int kMaxScoredPoints = 2000;
constexpr int kIcpIterations = 50;
// ICP stops once a step moves no point more than this share of the voxel, far below what the
// tracker's own registration, which starts from the pose, resolves: from there on the trimmed
// set's changes only make the pose jitter.
constexpr double kSettledMove = 1e-3;
// RefineAll refines in rounds of this many iterations, and after each drops the hypotheses
// still moving whose fit is worse than kDropRatio times the best so far (or than kDropRatio
// times kDropFloor voxels, where the cloud is so clean that the best is near zero): a wrong
// pose's trimmed pairs cycle to the cap, while a right one's fit is near the best.
constexpr int kRoundIterations = 10;
constexpr double kDropRatio = 3.0;
constexpr double kDropFloor = 0.1;
}  // namespace

PoseVerifier::PoseVerifier(const Vertices& y, const Triangles& tris, const Vertices& points,
                           const Eigen::Vector3d* eye, double voxel)
    : y_(y),
      tris_(tris),
      index_(y_, tris_),
      has_eye_(eye != nullptr),
      penalty_(2.0 * voxel),
      settled_(kSettledMove * voxel),
      drop_floor_(kDropFloor * voxel) {
  if (has_eye_) eye_ = *eye;
  face_normals_.resize(tris.rows(), 3);
  for (Eigen::Index f = 0; f < tris.rows(); ++f) {
    const Eigen::Vector3d a = y.row(tris(f, 0)), b = y.row(tris(f, 1)), c = y.row(tris(f, 2));
    face_normals_.row(f) = (b - a).cross(c - a).normalized().transpose();
  }
  const int stride = std::max<int>(1, static_cast<int>(points.rows()) / kMaxScoredPoints);
  for (Eigen::Index i = 0; i < points.rows(); i += stride)
    points_.push_back(points.row(i).transpose());
  if (has_eye_) all_points_ = points;
}

double PoseVerifier::Fit(const PoseHypothesis& h) const {
  std::vector<Eigen::Vector3d> a, b, n;
  return Pairs(h, &a, &b, &n);
}

void PoseVerifier::SetSurfaceSamples(const pcl::PointCloud<pcl::PointNormal>& model) {
  if (!has_eye_ || points_.empty()) return;
  for (const pcl::PointNormal& q : model) {
    samples_.emplace_back(q.x, q.y, q.z);
    sample_normals_.emplace_back(q.normal_x, q.normal_y, q.normal_z);
  }
  // Every point, not the scored ones: the nearest of a thinned cloud's points is about its
  // spacing away, which on a large object seen whole exceeds loss_scale by itself.
  cloud_index_ = std::make_unique<PointIndex>(all_points_);
}

double PoseVerifier::Coverage(const PoseHypothesis& h) const {
  if (!cloud_index_) return 0.0;
  const Eigen::Vector3d eye = h.R * eye_ + h.t;
  std::vector<double> d;
  for (size_t i = 0; i < samples_.size(); ++i) {
    const Eigen::Vector3d to_eye = eye - samples_[i];
    if (sample_normals_[i].dot(to_eye) <= 0.2 * to_eye.norm()) continue;
    double squared = 0.0;
    cloud_index_->Nearest(h.R.transpose() * (samples_[i] - h.t), &squared);
    d.push_back(std::sqrt(squared));
  }
  if (d.empty()) return 0.0;
  std::sort(d.begin(), d.end());
  const size_t keep = std::max<size_t>(1, static_cast<size_t>(0.7 * static_cast<double>(d.size())));
  double sum = 0.0;
  for (size_t j = 0; j < keep; ++j) sum += d[j];
  return sum / static_cast<double>(keep);
}

bool PoseVerifier::Refine(PoseHypothesis* h, int max_iterations) const {
  bool ended = false;
  for (int it = 0; it < std::min(max_iterations, kIcpIterations); ++it) {
    std::vector<Eigen::Vector3d> a, b, n;
    Pairs(*h, &a, &b, &n);
    if (a.size() < 6) {
      ended = true;  // nothing to refine with
      break;
    }
    // Linearized about the mapped points: (a + w x a + dt - b) . n = 0 in least squares.
    Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> Jtr = Eigen::Matrix<double, 6, 1>::Zero();
    for (size_t i = 0; i < a.size(); ++i) {
      Eigen::Matrix<double, 6, 1> J;
      J << a[i].cross(n[i]), n[i];
      JtJ += J * J.transpose();
      Jtr += J * (b[i] - a[i]).dot(n[i]);
    }
    JtJ.diagonal().array() += 1e-12 * JtJ.trace() + 1e-30;
    const Eigen::Matrix<double, 6, 1> x = JtJ.ldlt().solve(Jtr);
    if (!x.allFinite()) {
      ended = true;
      break;
    }
    const Eigen::Vector3d w = x.head<3>(), dt = x.tail<3>();
    const Eigen::Matrix3d dR = w.norm() > 0
                                   ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                                   : Eigen::Matrix3d::Identity();
    h->R = dR * h->R;
    h->t = dR * h->t + dt;
    // Settled: the step moved no mapped point more than settled_ (to first order). Past it
    // the trimmed set's changes make the pose jitter for the remaining iterations.
    double moved = 0.0;
    for (const Eigen::Vector3d& p : a) moved = std::max(moved, (w.cross(p) + dt).squaredNorm());
    if (std::sqrt(moved) <= settled_) {
      ended = true;
      break;
    }
  }
  h->fit = Score(*h);
  return ended;
}

void PoseVerifier::RefineAll(std::vector<PoseHypothesis>* batch, int threads,
                             double best_seen) const {
  const int n = static_cast<int>(batch->size());
  std::vector<char> active(static_cast<size_t>(n), 1);
  for (int done = 0; done < kIcpIterations; done += kRoundIterations) {
    std::vector<int> live;
    for (int i = 0; i < n; ++i) {
      if (active[static_cast<size_t>(i)]) live.push_back(i);
    }
    if (live.empty()) break;
    std::vector<char> ended(live.size(), 0);
    const int round = std::min(kRoundIterations, kIcpIterations - done);
    // Each on its own (the verifier only reads): the same results on any number of threads.
    RunTasks(threads, static_cast<int>(live.size()), [&](int k) {
      ended[static_cast<size_t>(k)] =
          Refine(&(*batch)[static_cast<size_t>(live[static_cast<size_t>(k)])], round);
    });
    double best = best_seen;
    for (const PoseHypothesis& h : *batch) best = std::min(best, h.fit);
    best = std::max(best, drop_floor_);
    for (size_t k = 0; k < live.size(); ++k) {
      const size_t i = static_cast<size_t>(live[k]);
      if (ended[k] || (*batch)[i].fit > kDropRatio * best) active[i] = 0;
    }
  }
}

double PoseVerifier::Pairs(const PoseHypothesis& h, std::vector<Eigen::Vector3d>* a,
                           std::vector<Eigen::Vector3d>* b, std::vector<Eigen::Vector3d>* n) const {
  const Eigen::Vector3d eye = h.R * eye_ + h.t;
  std::vector<std::pair<double, int>> dist;
  std::vector<Eigen::Vector3d> mapped(points_.size()), closest(points_.size());
  std::vector<int> triangle(points_.size(), -1);
  std::vector<char> back(points_.size(), 0);
  for (size_t i = 0; i < points_.size(); ++i) {
    mapped[i] = h.R * points_[i] + h.t;
    const SurfaceIndex::Hit hit = index_.Closest(mapped[i]);
    if (hit.triangle < 0) continue;
    double d = std::sqrt(hit.squared_distance);
    closest[i] = hit.point;
    triangle[i] = hit.triangle;
    if (has_eye_) {
      const Eigen::Vector3d to_eye = eye - hit.point;
      if (face_normals_.row(hit.triangle).dot(to_eye) < -0.2 * to_eye.norm()) {
        back[i] = 1;
        d = std::max(d, penalty_);
      }
    }
    dist.emplace_back(d, static_cast<int>(i));
  }
  if (dist.empty()) return std::numeric_limits<double>::infinity();
  std::sort(dist.begin(), dist.end());
  const size_t keep =
      std::max<size_t>(1, static_cast<size_t>(kKeep * static_cast<double>(dist.size())));
  double sum = 0.0;
  for (size_t j = 0; j < keep; ++j) {
    sum += dist[j].first;
    const size_t i = static_cast<size_t>(dist[j].second);
    if (back[i]) continue;
    a->push_back(mapped[i]);
    b->push_back(closest[i]);
    n->push_back(face_normals_.row(triangle[i]).transpose());
  }
  return sum / static_cast<double>(keep);
}

}  // namespace femreg
