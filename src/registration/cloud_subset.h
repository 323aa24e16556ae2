// Dropping points from a cloud in place, with their normals and labels.
#ifndef FEMREG_REGISTRATION_CLOUD_SUBSET_H_
#define FEMREG_REGISTRATION_CLOUD_SUBSET_H_

#include <functional>

#include "femreg/registration.h"

namespace femreg {

// Keeps the points i with keep(i) in their order (normals and labels with them); returns how
// many went.
int KeepPoints(const std::function<bool(int)>& keep, PointCloud* cloud);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_CLOUD_SUBSET_H_
