// Numbers the generators put into the tracking scenes they write.
#ifndef FEMREG_DATASETS_SCENE_NUMBERS_H_
#define FEMREG_DATASETS_SCENE_NUMBERS_H_

#include <Eigen/Core>
#include <cstdio>
#include <cstdlib>

namespace femreg {
namespace datasets_internal {

// x to `digits` significant digits (as printf's %.Ng writes it and strtod reads it back).
// The tracking scenes keep computed numbers (a gripper's path, a box just past a face) at
// the precision their scene files have always had, so that the bundled scenes read back
// to the same doubles whatever writes them.
inline double RoundSignificant(double x, int digits) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.*g", digits, x);
  return std::strtod(buf, nullptr);
}

inline Eigen::Vector3d RoundSignificant(const Eigen::Vector3d& v, int digits) {
  return Eigen::Vector3d(RoundSignificant(v.x(), digits), RoundSignificant(v.y(), digits),
                         RoundSignificant(v.z(), digits));
}

}  // namespace datasets_internal
}  // namespace femreg

#endif  // FEMREG_DATASETS_SCENE_NUMBERS_H_
