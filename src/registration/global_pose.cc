#include "registration/global_pose.h"

#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <random>
#include <unordered_map>
#include <utility>

#include "geometry/nearest.h"
#include "parallel/pool.h"
#include "registration/pose_verifier.h"

namespace femreg {
namespace {

using PclCloud = pcl::PointCloud<pcl::PointNormal>;
using Features = pcl::PointCloud<pcl::FPFHSignature33>;

// The sampling voxel of the features, in RMS distances of the object's vertices from their
// centroid (a size that does not change with the pose): fine enough for FPFH to tell the
// parts of a bunny apart, coarse enough for a RANSAC run of well under a second.
constexpr double kVoxelPerRadius = 0.1;
constexpr double kNormalRadius = 2.0;   // voxels
constexpr double kFeatureRadius = 5.0;  // voxels
// The RANSAC of Propose: each cloud sample's candidate matches (its nearest model samples in
// feature space), the pairs drawn, how alike two pairs' lengths must be and their normals'
// angles, the least fraction of the cloud's samples a kept pose brings within 1.5 voxels of
// the model's (a rough pose that ICP then refines), and how many distinct poses are refined.
constexpr int kMatches = 3;
constexpr int kDraws = 20000;
constexpr double kSimilarity = 0.9;
constexpr double kPairAngle = 15.0 * M_PI / 180.0;
constexpr double kMinInlierFraction = 0.15;
constexpr int kProposals = 16;
// A global pose replaces the given one only if it explains the cloud this much better.
constexpr double kWinRatio = 0.5;
// Two poses whose rotations differ by more than this, with fits within this ratio, are an
// ambiguity (a symmetric object).
constexpr double kDistinctAngle = 20.0 * M_PI / 180.0;
constexpr double kAmbiguousRatio = 1.25;

struct VoxelKey {
  size_t operator()(const std::array<long long, 3>& k) const {
    return static_cast<size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
  }
};

// The first point (in their order) of every voxel of side v the points occupy.
std::vector<int> VoxelPick(const Vertices& p, double v) {
  std::unordered_map<std::array<long long, 3>, int, VoxelKey> seen;
  std::vector<int> kept;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const std::array<long long, 3> key = {static_cast<long long>(std::floor(p(i, 0) / v)),
                                          static_cast<long long>(std::floor(p(i, 1) / v)),
                                          static_cast<long long>(std::floor(p(i, 2) / v))};
    if (seen.emplace(key, static_cast<int>(i)).second) kept.push_back(static_cast<int>(i));
  }
  return kept;
}

// FPFH features of c (its normals set); points without enough neighbours for a feature are
// dropped from both.
void Describe(double radius, PclCloud::Ptr* c, Features::Ptr* f) {
  pcl::FPFHEstimation<pcl::PointNormal, pcl::PointNormal, pcl::FPFHSignature33> fpfh;
  fpfh.setInputCloud(*c);
  fpfh.setInputNormals(*c);
  fpfh.setRadiusSearch(radius);
  Features all;
  fpfh.compute(all);
  PclCloud::Ptr kept(new PclCloud);
  Features::Ptr features(new Features);
  for (size_t i = 0; i < all.size(); ++i) {
    bool finite = true;
    for (float h : all[i].histogram) finite = finite && std::isfinite(h);
    if (!finite) continue;
    kept->push_back((**c)[i]);
    features->push_back(all[i]);
  }
  *c = kept;
  *f = features;
}

pcl::PointNormal MakePoint(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
  pcl::PointNormal q;
  q.x = static_cast<float>(p.x());
  q.y = static_cast<float>(p.y());
  q.z = static_cast<float>(p.z());
  q.normal_x = static_cast<float>(n.x());
  q.normal_y = static_cast<float>(n.y());
  q.normal_z = static_cast<float>(n.z());
  q.curvature = 0.0f;
  return q;
}

// The surface sampled for its features: a barycentric grid on every triangle, half a voxel
// apart or finer (a coarse mesh's vertices alone describe its shape worse than the cloud
// does), with the triangle's normal, one per voxel.
PclCloud::Ptr ModelSamples(const Vertices& y, const Triangles& tris, double voxel) {
  std::vector<Eigen::Vector3d> points, normals;
  for (Eigen::Index f = 0; f < tris.rows(); ++f) {
    const Eigen::Vector3d a = y.row(tris(f, 0)), b = y.row(tris(f, 1)), c = y.row(tris(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    if (!n.allFinite()) continue;
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int m = std::max(1, static_cast<int>(std::ceil(longest / (0.5 * voxel))));
    for (int i = 0; i <= m; ++i) {
      for (int j = 0; i + j <= m; ++j) {
        points.push_back(a + (b - a) * (static_cast<double>(i) / m) +
                         (c - a) * (static_cast<double>(j) / m));
        normals.push_back(n);
      }
    }
  }
  Vertices all(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i)
    all.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  PclCloud::Ptr out(new PclCloud);
  for (int i : VoxelPick(all, voxel))
    out->push_back(MakePoint(points[static_cast<size_t>(i)], normals[static_cast<size_t>(i)]));
  return out;
}

// The cloud sampled one point per voxel, with normals from its neighbours within
// kNormalRadius voxels in the whole cloud, turned towards the eye (or away from the cloud's
// centroid without one).
PclCloud::Ptr CloudSamples(const Vertices& points, const Eigen::Vector3d* eye, double voxel) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr all(new pcl::PointCloud<pcl::PointXYZ>);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    all->push_back(pcl::PointXYZ(static_cast<float>(points(i, 0)), static_cast<float>(points(i, 1)),
                                 static_cast<float>(points(i, 2))));
  }
  pcl::PointCloud<pcl::PointXYZ>::Ptr picked(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i : VoxelPick(points, voxel)) picked->push_back((*all)[static_cast<size_t>(i)]);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimate;
  estimate.setInputCloud(picked);
  estimate.setSearchSurface(all);
  estimate.setRadiusSearch(kNormalRadius * voxel);
  pcl::PointCloud<pcl::Normal> normals;
  estimate.compute(normals);
  const Eigen::Vector3d centroid = points.colwise().mean().transpose();
  PclCloud::Ptr out(new PclCloud);
  for (size_t i = 0; i < picked->size(); ++i) {
    const pcl::PointXYZ& q = (*picked)[i];
    const Eigen::Vector3d p(q.x, q.y, q.z);
    Eigen::Vector3d n(normals[i].normal_x, normals[i].normal_y, normals[i].normal_z);
    if (!n.allFinite() || n.norm() == 0) continue;
    const Eigen::Vector3d out_dir =
        eye != nullptr ? Eigen::Vector3d(*eye - p) : Eigen::Vector3d(p - centroid);
    if (n.dot(out_dir) < 0) n = -n;
    out->push_back(MakePoint(p, n));
  }
  return out;
}

double RotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle();
}

// Rough poses of the cloud on the model by RANSAC over FPFH matches, many kept, not one: each
// draw takes two cloud samples, each with one of its kMatches nearest model samples in feature
// space; two oriented points fix a pose, and the draw is dropped unless the two pairs' lengths
// and their normals' angles (the point-pair feature) agree. A pose is kept if it brings
// kMinInlierFraction of the cloud's samples within 1.5 voxels of the model's; returns the
// distinct kept poses with the most inliers, most first. (PCL's SampleConsensusPrerejective
// keeps one pose per run, and on a body of many alike parts it often reached its inlier
// fraction in no run: the true pose was never proposed.) Draws from a fixed-seed std::mt19937:
// the same poses on every run and thread count.
std::vector<PoseHypothesis> Propose(const PclCloud& cloud, const Features& cloud_features,
                                    const PclCloud::Ptr& model, const Features::Ptr& model_features,
                                    double voxel, int threads) {
  std::vector<PoseHypothesis> out;
  const int n = static_cast<int>(cloud.size());
  if (n < 3 || model->size() < 3) return out;
  auto position = [](const pcl::PointNormal& q) { return Eigen::Vector3d(q.x, q.y, q.z); };
  auto normal = [](const pcl::PointNormal& q) {
    return Eigen::Vector3d(q.normal_x, q.normal_y, q.normal_z).normalized();
  };
  // Each cloud sample's candidate matches.
  pcl::KdTreeFLANN<pcl::FPFHSignature33> feature_tree;
  feature_tree.setInputCloud(model_features);
  std::vector<std::vector<int>> matches(static_cast<size_t>(n));
  std::vector<float> squared;
  for (int i = 0; i < n; ++i) {
    feature_tree.nearestKSearch(cloud_features[static_cast<size_t>(i)], kMatches,
                                matches[static_cast<size_t>(i)], squared);
  }
  Vertices model_points(static_cast<Eigen::Index>(model->size()), 3);
  for (size_t i = 0; i < model->size(); ++i)
    model_points.row(static_cast<Eigen::Index>(i)) = position((*model)[i]).transpose();
  const PointIndex model_index(model_points);
  std::vector<Eigen::Vector3d> c, cn;
  for (const pcl::PointNormal& q : cloud) {
    c.push_back(position(q));
    cn.push_back(normal(q));
  }
  std::mt19937 rng(1);
  auto draw = [&rng](size_t size) { return static_cast<size_t>(rng() % size); };
  // The inliers are counted in a shuffled order, so that a poor pose is dropped after a few.
  std::vector<int> order(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
  for (size_t i = order.size() - 1; i > 0; --i) std::swap(order[i], order[draw(i + 1)]);
  const double inlier_squared = (1.5 * voxel) * (1.5 * voxel);
  const int early = std::min(n, 30);
  // The frame of an oriented pair: along the pair, the first normal's part across it, and
  // their cross product.
  auto frame = [](const Eigen::Vector3d& d, const Eigen::Vector3d& n0, Eigen::Matrix3d* F) {
    const Eigen::Vector3d e1 = d.normalized();
    const Eigen::Vector3d across = n0 - n0.dot(e1) * e1;
    if (!(across.norm() > 0.1)) return false;  // the normal nearly along the pair
    F->col(0) = e1;
    F->col(1) = across.normalized();
    F->col(2) = e1.cross(F->col(1));
    return true;
  };
  auto agree = [](double cos_a, double cos_b) {
    return std::abs(std::acos(std::clamp(cos_a, -1.0, 1.0)) -
                    std::acos(std::clamp(cos_b, -1.0, 1.0))) <= kPairAngle;
  };
  struct Candidate {
    int inliers;
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
  };
  // The draws first, in the random sequence's order (a draw whose samples have no match draws
  // no model points); then each draw's pose and inlier count on its own, on several threads:
  // the same candidates, in the same order, on any thread count.
  struct Draw {
    size_t s0 = 0, s1 = 0;
    int m0 = -1, m1 = -1;  // -1: a sample without a match
  };
  std::vector<Draw> draws(static_cast<size_t>(kDraws));
  for (Draw& d : draws) {
    d.s0 = draw(c.size());
    d.s1 = draw(c.size());
    if (matches[d.s0].empty() || matches[d.s1].empty()) continue;
    d.m0 = matches[d.s0][draw(matches[d.s0].size())];
    d.m1 = matches[d.s1][draw(matches[d.s1].size())];
  }
  std::vector<Candidate> found(draws.size());
  ParallelFor(threads, static_cast<int64_t>(draws.size()), 1024, [&](int64_t it) {
    const Draw& d = draws[static_cast<size_t>(it)];
    Candidate& out_candidate = found[static_cast<size_t>(it)];
    out_candidate.inliers = -1;  // none
    if (d.m0 < 0) return;
    const size_t s0 = d.s0, s1 = d.s1;
    const pcl::PointNormal& q0 = (*model)[static_cast<size_t>(d.m0)];
    const pcl::PointNormal& q1 = (*model)[static_cast<size_t>(d.m1)];
    const Eigen::Vector3d dc = c[s1] - c[s0], dm = position(q1) - position(q0);
    const double lc = dc.norm(), lm = dm.norm();
    if (!(lc > 2.0 * voxel) || std::min(lc, lm) < kSimilarity * std::max(lc, lm)) return;
    const Eigen::Vector3d mn0 = normal(q0), mn1 = normal(q1);
    if (!agree(cn[s0].dot(dc) / lc, mn0.dot(dm) / lm) ||
        !agree(cn[s1].dot(dc) / lc, mn1.dot(dm) / lm) || !agree(cn[s0].dot(cn[s1]), mn0.dot(mn1))) {
      return;
    }
    Eigen::Matrix3d Fc, Fm;
    if (!frame(dc, cn[s0], &Fc) || !frame(dm, mn0, &Fm)) return;
    const Eigen::Matrix3d R = Fm * Fc.transpose();
    const Eigen::Vector3d t = 0.5 * (position(q0) + position(q1)) - R * (0.5 * (c[s0] + c[s1]));
    int inliers = 0, checked = 0;
    for (int i : order) {
      double d2 = 0.0;
      model_index.Nearest(R * c[static_cast<size_t>(i)] + t, &d2);
      inliers += d2 < inlier_squared ? 1 : 0;
      ++checked;
      if (checked == early && inliers < kMinInlierFraction * early) break;
    }
    if (checked == n && inliers >= kMinInlierFraction * n) out_candidate = {inliers, R, t};
  });
  std::vector<Candidate> candidates;
  for (const Candidate& k : found) {
    if (k.inliers >= 0) candidates.push_back(k);
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.inliers > b.inliers; });
  // Distinct: turned by more than kDistinctAngle, or putting the cloud's centroid 2 voxels
  // elsewhere (ICP takes a pose closer than that to the same place).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : c) centroid += p;
  centroid /= static_cast<double>(n);
  for (const Candidate& k : candidates) {
    bool distinct = true;
    for (const PoseHypothesis& h : out) {
      distinct =
          distinct && (RotationAngle(k.R, h.R) > kDistinctAngle ||
                       ((k.R * centroid + k.t) - (h.R * centroid + h.t)).norm() > 2.0 * voxel);
    }
    if (!distinct) continue;
    PoseHypothesis h;
    h.R = k.R;
    h.t = k.t;
    out.push_back(h);
    if (static_cast<int>(out.size()) == kProposals) break;
  }
  return out;
}

}  // namespace

GlobalPoseResult GlobalPose(const Vertices& points, const Eigen::Vector3d* eye, int object,
                            TrackerState* state, const DataSurface* surface) {
  GlobalPoseResult result;
  const ObjectState& o = state->objects[static_cast<size_t>(object)];
  const int nv = o.mesh.num_vertices();
  const Vertices mesh_y = state->x.middleRows(o.offset, nv);
  // The surface the pose is fitted with: the embedded one if the object has it.
  const bool embedded = surface != nullptr && surface->embedded(object);
  const Vertices y = embedded ? surface->ObjectPositions(object) : mesh_y;
  const Triangles tris = embedded ? surface->ObjectSurface(object) : o.mesh.surface;
  if (points.rows() < 3 || tris.rows() == 0) return result;
  // The mean first: inside the expression Eigen sums the column again per row (quadratic).
  const Eigen::RowVector3d mean = y.colwise().mean();
  const double radius = std::sqrt((y.rowwise() - mean).rowwise().squaredNorm().mean());
  const double voxel = kVoxelPerRadius * radius;
  PoseVerifier verifier(y, tris, points, eye, voxel);
  // The check counts the surface facing the eye too: a pose turned by a fraction of a radian
  // can leave a partial view within loss_scale of some part of a large body's surface.
  PclCloud::Ptr model = ModelSamples(y, tris, voxel);
  verifier.SetSurfaceSamples(*model);
  const double given_score = verifier.Score(PoseHypothesis());
  result.given_fit = given_score;
  if (!(given_score > state->options.data.loss_scale)) return result;
  result.searched = true;

  // The given pose refined locally is a hypothesis like the global ones.
  const int threads = state->options.solver.num_threads;
  PclCloud::Ptr cloud = CloudSamples(points, eye, voxel);
  Features::Ptr model_features, cloud_features;
  RunTasks(threads, 2, [&](int which) {  // two estimators of their own: side by side
    if (which == 0) {
      Describe(kFeatureRadius * voxel, &model, &model_features);
    } else {
      Describe(kFeatureRadius * voxel, &cloud, &cloud_features);
    }
  });
  std::vector<PoseHypothesis> hypotheses(1);
  for (const PoseHypothesis& h : Propose(*cloud, *cloud_features, model, model_features, voxel, threads)) hypotheses.push_back(h);
  verifier.RefineAll(&hypotheses, threads);
  auto by_fit = [](const PoseHypothesis& a, const PoseHypothesis& b) { return a.fit < b.fit; };
  std::stable_sort(hypotheses.begin(), hypotheses.end(), by_fit);
  // A symmetric body's other poses are the best one turned by half a turn about one of its
  // principal axes: tried as hypotheses too, so that the ambiguity shows whether or not RANSAC
  // happened to find them.
  const Eigen::Vector3d centre = mean.transpose();
  const Eigen::Matrix3d covariance =
      (y.rowwise() - centre.transpose()).transpose() * (y.rowwise() - centre.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes(covariance);
  const PoseHypothesis first = hypotheses.front();
  std::vector<PoseHypothesis> turned(3);
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d half =
        Eigen::AngleAxisd(M_PI, axes.eigenvectors().col(k)).toRotationMatrix();
    PoseHypothesis& h = turned[static_cast<size_t>(k)];
    h.R = half * first.R;
    h.t = half * (first.t - centre) + centre;
  }
  verifier.RefineAll(&turned, threads, hypotheses.front().fit);
  hypotheses.insert(hypotheses.end(), turned.begin(), turned.end());
  std::stable_sort(hypotheses.begin(), hypotheses.end(), by_fit);
  const PoseHypothesis& best = hypotheses.front();
  for (size_t i = 1; i < hypotheses.size(); ++i) {
    if (RotationAngle(hypotheses[i].R, best.R) > kDistinctAngle) {
      result.ambiguous = hypotheses[i].fit < kAmbiguousRatio * best.fit;
      break;
    }
  }
  result.hypotheses = hypotheses;
  // Of the poses that explain the cloud about as well as the best (a symmetric body's), the
  // one turned least from the given pose: after a loss the given pose is the last good one,
  // and its turned copies would put every vertex elsewhere on the same surface.
  const PoseHypothesis* chosen = &best;
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  for (const PoseHypothesis& h : hypotheses) {
    if (h.fit < kAmbiguousRatio * best.fit &&
        RotationAngle(h.R, identity) < RotationAngle(chosen->R, identity)) {
      chosen = &h;
    }
  }
  // The given pose also stands where the cloud covers what the camera should see of the body
  // better there than at the chosen pose, by the same ratio: the chosen one fits the cloud
  // better only by explaining points that are not the body's. A hand in the mask can be most
  // of the cloud, more than the trimmed fit leaves out.
  // (0: no eye, or nothing of the given pose's surface faces it; then the fit alone decides.)
  const double given_coverage = verifier.Coverage(PoseHypothesis());
  const bool covered_better = given_coverage > 0.0 && given_coverage < kWinRatio * verifier.Coverage(*chosen);
  if (!(chosen->fit < kWinRatio * given_score) || covered_better) {
    result.ambiguous = false;  // the given pose stands: which other pose fits does not matter
    return result;
  }
  // q = R p + t maps the cloud onto the surface as given: the surface goes by the inverse.
  result.moved = true;
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d p = mesh_y.row(v).transpose();
    state->x.row(o.offset + v) = (chosen->R.transpose() * (p - chosen->t)).transpose();
  }
  return result;
}

void ChooseInitialPose(const PointCloud& cloud, TrackerState* state, FrameSummary* summary,
                       DataSurface* surface) {
  const RegistrationOptions& options = state->options;
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  const Eigen::Vector3d* eye_ptr = nullptr;
  if (options.camera.enabled) {
    eye = options.camera.position;
    eye_ptr = &eye;
  } else if (cloud.has_viewpoint) {
    eye = cloud.viewpoint;
    eye_ptr = &eye;
  }
  bool searched = false, moved = false;
  for (size_t i = 0; i < state->objects.size(); ++i) {
    const ObjectState& o = state->objects[i];
    bool anchored = false;
    for (const auto& a : state->anchors)
      anchored = anchored || a.second.object == static_cast<int>(i);
    if (anchored) continue;  // anchors hold the object where it is given
    Vertices points;
    if (state->objects.size() == 1) {
      points = cloud.points;
    } else if (o.label >= 0 && cloud.has_labels()) {
      std::vector<int> mine;
      for (int p = 0; p < cloud.size(); ++p) {
        if (cloud.labels(p) == o.label) mine.push_back(p);
      }
      points.resize(static_cast<Eigen::Index>(mine.size()), 3);
      for (size_t k = 0; k < mine.size(); ++k)
        points.row(static_cast<Eigen::Index>(k)) = cloud.points.row(mine[k]);
    } else {
      continue;  // which points are this object's is not known
    }
    if (surface != nullptr) surface->Update(state->x);
    const GlobalPoseResult r = GlobalPose(points, eye_ptr, static_cast<int>(i), state, surface);
    searched = searched || r.searched;
    moved = moved || r.moved;
    summary->pose_ambiguous = summary->pose_ambiguous || r.ambiguous;
  }
  summary->initial_pose = moved ? "global" : searched ? "given, searched" : "given";
}

}  // namespace femreg
