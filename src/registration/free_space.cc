#include "registration/free_space.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace femreg {

namespace {

constexpr double kNear = 1e-4;       // m: nearer points are behind the sensor's plane
constexpr int kMaxImageSide = 1024;  // pixels; a coarser pitch beyond it
constexpr int kSplat = 1;            // a point covers the pixels within this many of its own

// Rows: two image axes and `axis`, a right-handed orthonormal frame.
Eigen::Matrix3d FrameAlong(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d z = axis.normalized();
  const Eigen::Vector3d helper = std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = helper.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  return R;
}

}  // namespace

bool ObservedDepth::Project(const Eigen::Vector3d& p, double* u, double* v, double* depth) const {
  if (perspective_) {
    const Eigen::Vector3d q = rotation_ * (p - eye_);
    if (!(q.z() > kNear)) return false;
    *u = q.x() / q.z();
    *v = q.y() / q.z();
    *depth = (p - eye_).norm();
  } else {
    const Eigen::Vector3d q = rotation_ * p;
    *u = q.x();
    *v = q.y();
    *depth = q.z();
  }
  *u = (*u - u0_) / pitch_;
  *v = (*v - v0_) / pitch_;
  return std::isfinite(*u) && std::isfinite(*v) && std::isfinite(*depth);
}

void ObservedDepth::Build(const Vertices& points, bool perspective, const Eigen::Vector3d& eye,
                          const Eigen::Vector3d& axis, double spacing, const Vertices* also) {
  Clear();
  perspective_ = perspective;
  eye_ = perspective ? eye : Eigen::Vector3d::Zero();
  rotation_ = FrameAlong(perspective ? axis : Eigen::Vector3d(-eye));
  u0_ = v0_ = 0.0;
  pitch_ = 1.0;
  const int n = static_cast<int>(points.rows());
  if (n == 0 || !(spacing > 0)) return;
  const int n_also = also != nullptr ? static_cast<int>(also->rows()) : 0;
  std::vector<double> us, vs, ds;
  us.reserve(static_cast<size_t>(n + n_also));
  vs.reserve(static_cast<size_t>(n + n_also));
  ds.reserve(static_cast<size_t>(n + n_also));
  double lo_u = std::numeric_limits<double>::infinity(), hi_u = -lo_u, lo_v = lo_u, hi_v = -lo_u;
  size_t own = 0;  // the first `own` projections are `points`'s
  for (int i = 0; i < n + n_also; ++i) {
    double u = 0, v = 0, d = 0;
    if (!Project(i < n ? points.row(i) : also->row(i - n), &u, &v, &d)) continue;
    lo_u = std::min(lo_u, u);
    hi_u = std::max(hi_u, u);
    lo_v = std::min(lo_v, v);
    hi_v = std::max(hi_v, v);
    us.push_back(u);
    vs.push_back(v);
    ds.push_back(d);
    if (i < n) ++own;
  }
  if (own == 0) return;
  // The pitch: one point spacing at the points' median depth, so that neighbouring points
  // fall about a pixel apart and their splats close the gaps between them.
  double pitch = spacing;
  if (perspective) {
    std::vector<double> sorted(ds.begin(), ds.begin() + static_cast<std::ptrdiff_t>(own));
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    pitch = spacing / std::max(sorted[sorted.size() / 2], kNear);
  }
  pitch = std::max({pitch, (hi_u - lo_u) / (kMaxImageSide - 2 * kSplat - 3),
                    (hi_v - lo_v) / (kMaxImageSide - 2 * kSplat - 3), 1e-12});
  pitch_ = pitch;
  u0_ = lo_u - (kSplat + 1) * pitch;
  v0_ = lo_v - (kSplat + 1) * pitch;
  width_ = static_cast<int>(std::ceil((hi_u - lo_u) / pitch)) + 2 * kSplat + 3;
  height_ = static_cast<int>(std::ceil((hi_v - lo_v) / pitch)) + 2 * kSplat + 3;
  depth_.assign(static_cast<size_t>(width_) * static_cast<size_t>(height_),
                std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < ds.size(); ++i) {
    const int px = static_cast<int>(std::lround((us[i] - u0_) / pitch_));
    const int py = static_cast<int>(std::lround((vs[i] - v0_) / pitch_));
    for (int y = std::max(0, py - kSplat); y <= std::min(height_ - 1, py + kSplat); ++y) {
      for (int x = std::max(0, px - kSplat); x <= std::min(width_ - 1, px + kSplat); ++x) {
        double& d = depth_[static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)];
        d = std::min(d, ds[i]);
      }
    }
  }
}

bool ObservedDepth::Observed(const Eigen::Vector3d& p, Eigen::Vector3d* ray, Eigen::Vector3d* origin,
                             double* depth) const {
  if (depth_.empty()) return false;
  double u = 0, v = 0, d = 0;
  if (!Project(p, &u, &v, &d)) return false;
  const long px = std::lround(u), py = std::lround(v);
  if (px < 0 || py < 0 || px >= width_ || py >= height_) return false;
  const double observed = depth_[static_cast<size_t>(py) * static_cast<size_t>(width_) + static_cast<size_t>(px)];
  if (!std::isfinite(observed)) return false;
  if (perspective_) {
    *ray = (p - eye_).normalized();
    *origin = eye_;
  } else {
    *ray = rotation_.row(2).transpose();
    *origin = Eigen::Vector3d::Zero();
  }
  *depth = observed;
  return true;
}

double ObservedDepth::SidewaysExit(const Eigen::Vector3d& p, double tolerance, double limit) const {
  const double none = std::numeric_limits<double>::infinity();
  if (depth_.empty()) return none;
  double u = 0, v = 0, d = 0;
  if (!Project(p, &u, &v, &d)) return none;
  const long px = std::lround(u), py = std::lround(v);
  const double metres_per_pixel = perspective_ ? pitch_ * d : pitch_;
  if (!(metres_per_pixel > 0)) return none;
  const long rings = static_cast<long>(std::min(limit / metres_per_pixel, 4.0 * kMaxImageSide)) + 1;
  // Ring by ring (the square ring at Chebyshev distance r), the nearest allowed pixel's
  // Euclidean distance; a later ring cannot beat r times the pitch.
  double best = none;
  for (long r = 1; r <= rings; ++r) {
    if (r * metres_per_pixel >= best) break;
    for (long y = py - r; y <= py + r; ++y) {
      const bool edge_row = y == py - r || y == py + r;
      for (long x = px - r; x <= px + r; x += edge_row ? 1 : 2 * r) {
        bool allowed = x < 0 || y < 0 || x >= width_ || y >= height_;
        if (!allowed) {
          const double observed = depth_[static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)];
          allowed = !std::isfinite(observed) || observed - tolerance <= d;
        }
        if (!allowed) continue;
        const double du = static_cast<double>(x) - u, dv = static_cast<double>(y) - v;
        best = std::min(best, std::sqrt(du * du + dv * dv) * metres_per_pixel);
      }
    }
  }
  return best <= limit ? best : none;
}

}  // namespace femreg
