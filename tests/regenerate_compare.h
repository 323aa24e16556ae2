// Comparing a regenerated dataset file with the bundled one by what it means rather than by
// its bytes (tests that bundled datasets regenerate: collision_sequences_test.cc, synth_test.cc).
//
// Floating-point results differ across CPUs and BLAS builds in their last digits (OpenBLAS
// picks its kernels by CPU at run time, and CHOLMOD factorizes through it), and a solve
// amplifies those digits by its conditioning. So positions are compared with a tolerance
// that each test argues from its solve, while what is integer by construction (vertex and
// triangle counts, connectivity, the rows of a file) is compared exactly.
#ifndef FEMREG_TESTS_REGENERATE_COMPARE_H_
#define FEMREG_TESTS_REGENERATE_COMPARE_H_

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/eval.h"
#include "femreg/ground_truth.h"
#include "femreg/point_cloud.h"

namespace femreg {
namespace regen {

// How far a regenerated file lies from the bundled one (metres).
struct Deviation {
  bool ok = false;      // both files read, and their integer structure agrees
  std::string problem;  // why not
  double max = 0.0;     // largest distance of a point
  double mean = 0.0;    // mean distance
  int count = 0;        // points (or vertices) in the bundled file
  int count_other = 0;  // ... and in the regenerated one
  int flips = 0;        // ground truth: vertices whose visibility differs
  std::string Report() const {
    std::ostringstream os;
    if (!ok) return "not comparable: " + problem;
    os << count << " vs " << count_other << " points, max " << max << " m, mean " << mean
       << " m, " << flips << " visibility flips";
    return os.str();
  }
};

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Per-vertex distances of two ground-truth frames (`femreg synth` / `contact-data` CSVs):
// the same vertices in the same order, so rows must match one for one.
inline Deviation CompareGroundTruth(const std::string& bundled, const std::string& regenerated) {
  Deviation d;
  GroundTruthFrame a, b;
  Status s = ReadGroundTruthFrame(bundled, &a);
  if (s.ok()) s = ReadGroundTruthFrame(regenerated, &b);
  if (!s.ok()) {
    d.problem = s.message();
    return d;
  }
  d.count = static_cast<int>(a.positions.rows());
  d.count_other = static_cast<int>(b.positions.rows());
  if (d.count != d.count_other) {
    d.problem = "different vertex counts";
    return d;
  }
  for (int v = 0; v < d.count; ++v) {
    const double dist = (a.positions.row(v) - b.positions.row(v)).norm();
    d.max = std::max(d.max, dist);
    d.mean += dist / std::max(1, d.count);
    if (v < static_cast<int>(a.visible.size()) && v < static_cast<int>(b.visible.size()) &&
        a.visible[v] != b.visible[v]) {
      ++d.flips;
    }
  }
  d.ok = true;
  return d;
}

// Two clouds of the same scene through the same camera: the distance from every point of
// each to the nearest point of the other (both ways, brute force: clouds here have a few
// thousand points). Their counts may differ where a pixel sees a silhouette or a grazing
// surface and the surface moved by a hair; the caller bounds that separately.
inline Deviation CompareClouds(const std::string& bundled, const std::string& regenerated) {
  Deviation d;
  PointCloud a, b;
  Status s = ReadPointCloud(bundled, &a);
  if (s.ok()) s = ReadPointCloud(regenerated, &b);
  if (!s.ok()) {
    d.problem = s.message();
    return d;
  }
  d.count = a.size();
  d.count_other = b.size();
  if (a.size() == 0 || b.size() == 0) {
    d.ok = a.size() == b.size();
    d.problem = "one cloud is empty";
    return d;
  }
  double sum = 0.0;
  auto one_way = [&](const PointCloud& from, const PointCloud& to) {
    for (int i = 0; i < from.size(); ++i) {
      double best = INFINITY;
      for (int j = 0; j < to.size(); ++j) best = std::min(best, (from.points.row(i) - to.points.row(j)).squaredNorm());
      best = std::sqrt(best);
      d.max = std::max(d.max, best);
      sum += best;
    }
  };
  one_way(a, b);
  one_way(b, a);
  d.mean = sum / (a.size() + b.size());
  d.ok = true;
  return d;
}

// How many points of either cloud lie farther than `distance` from every point of the other.
inline int FartherThan(const std::string& bundled, const std::string& regenerated, double distance) {
  PointCloud a, b;
  if (!ReadPointCloud(bundled, &a).ok() || !ReadPointCloud(regenerated, &b).ok()) return -1;
  int far = 0;
  auto one_way = [&](const PointCloud& from, const PointCloud& to) {
    for (int i = 0; i < from.size(); ++i) {
      bool near = false;
      for (int j = 0; j < to.size() && !near; ++j) {
        near = (from.points.row(i) - to.points.row(j)).squaredNorm() <= distance * distance;
      }
      far += near ? 0 : 1;
    }
  };
  one_way(a, b);
  one_way(b, a);
  return far;
}

// Whether a regenerated cloud of a virtual depth camera (DepthSensor::Sample) agrees with
// the bundled one, and if not, why. The camera sees the ground-truth surface, so its points
// move with it, by up to 1/cos(80 deg) = 5.8 times as much at the steepest angle it keeps;
// a pixel at a silhouette or at that angle may appear or vanish; and since the noise draws
// come from one seeded sequence in pixel order, every pixel after such a flip draws another
// depth noise (sigma_z = 2.85e-3 z^2 = 0.26 mm at 0.3 m). So: the counts agree within 1%,
// at most 2% of the points lie farther than 1 mm (about 4 sigma) from the other cloud, and
// the mean distance stays below 0.25 mm (about sigma).
inline bool CloudsAgree(const std::string& bundled, const std::string& regenerated, std::string* why) {
  const Deviation d = CompareClouds(bundled, regenerated);
  std::ostringstream os;
  os << d.Report();
  if (!d.ok) {
    *why = os.str();
    return false;
  }
  const int far = FartherThan(bundled, regenerated, 1e-3);
  os << ", " << far << " points farther than 1 mm";
  *why = os.str();
  return std::abs(d.count - d.count_other) <= d.count / 100 && far <= (d.count + d.count_other) / 50 &&
         d.mean <= 0.25e-3;
}

// Two VTU surfaces (`femreg synth` truth/*.vtu): the same points in the same order and the
// same triangles exactly; the points' distances.
inline Deviation CompareVtuSurfaces(const std::string& bundled, const std::string& regenerated) {
  Deviation d;
  VtuGeometry a, b;
  Status s = ReadVtuGeometry(bundled, &a);
  if (s.ok()) s = ReadVtuGeometry(regenerated, &b);
  if (!s.ok()) {
    d.problem = s.message();
    return d;
  }
  d.count = static_cast<int>(a.points.rows());
  d.count_other = static_cast<int>(b.points.rows());
  if (d.count != d.count_other || a.surface.rows() != b.surface.rows() || a.surface != b.surface ||
      a.tets.rows() != b.tets.rows() || a.tets != b.tets) {
    d.problem = "different points, triangles or tetrahedra";
    return d;
  }
  for (int v = 0; v < d.count; ++v) {
    const double dist = (a.points.row(v) - b.points.row(v)).norm();
    d.max = std::max(d.max, dist);
    d.mean += dist / std::max(1, d.count);
  }
  d.ok = true;
  return d;
}

}  // namespace regen
}  // namespace femreg

#endif  // FEMREG_TESTS_REGENERATE_COMPARE_H_
