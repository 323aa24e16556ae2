// Keyframed obstacle poses and the collision options' ranges (the collision section of a
// scene, femreg/collision_spec.h).
#include "femreg/collision_spec.h"

#include "femreg/geometry.h"

namespace femreg {

bool CollisionSpec::IsValid(std::string* error) const { return CheckFieldRanges(*this, error); }

Eigen::Isometry3d ObstaclePose(const std::vector<ObstacleKeyframe>& keyframes, double frame) {
  auto pose = [](const ObstacleKeyframe& k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = RotationFromVector(k.rotation);
    T.translation() = k.translation;
    return T;
  };
  if (keyframes.empty()) return Eigen::Isometry3d::Identity();
  if (frame <= keyframes.front().frame) return pose(keyframes.front());
  if (frame >= keyframes.back().frame) return pose(keyframes.back());
  size_t i = 0;
  while (i + 1 < keyframes.size() && keyframes[i + 1].frame <= frame) ++i;
  const ObstacleKeyframe& a = keyframes[i];
  const ObstacleKeyframe& b = keyframes[i + 1];
  const double s = (frame - a.frame) / static_cast<double>(b.frame - a.frame);
  const Eigen::Quaterniond qa(pose(a).linear()), qb(pose(b).linear());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = qa.slerp(s, qb).toRotationMatrix();
  T.translation() = (1 - s) * a.translation + s * b.translation;
  return T;
}

}  // namespace femreg
